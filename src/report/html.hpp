#pragma once
// Text that goes into the HTML reports as written: a name, a message or a log line may hold
// characters HTML reads as markup.
#include <string>
#include <string_view>

namespace epa::report {

// <, > and & as entities: text inside an element.
std::string escape_html(std::string_view text);
// The same and " as &quot;: text that may also stand inside a quoted attribute.
std::string escape_html_attribute(std::string_view text);

}  // namespace epa::report
