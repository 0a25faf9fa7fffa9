#include "report/html.hpp"

namespace epa::report {

namespace {
std::string escape(std::string_view text, bool quotes) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"' && quotes) out += "&quot;";
    else out += c;
  }
  return out;
}
}  // namespace

std::string escape_html(std::string_view text) { return escape(text, false); }
std::string escape_html_attribute(std::string_view text) { return escape(text, true); }

std::string inline_svg(const std::string& svg) {
  const auto p = svg.find("<svg");
  return p == std::string::npos ? svg : svg.substr(p);
}

}  // namespace epa::report
