#pragma once
// Text and pictures that go into the HTML reports: a name, a message or a log line may hold
// characters HTML reads as markup; an SVG document carries a prolog HTML does not take.
#include <string>
#include <string_view>

namespace epa::report {

// <, > and & as entities: text inside an element.
std::string escape_html(std::string_view text);
// The same and " as &quot;: text that may also stand inside a quoted attribute.
std::string escape_html_attribute(std::string_view text);
// An SVG document without its XML prolog, to inline in an HTML page.
std::string inline_svg(const std::string& svg);

}  // namespace epa::report
