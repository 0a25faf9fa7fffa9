#include "core/printable_name.hpp"

#include <cstdint>
#include <cstdio>

#include "core/utf8.hpp"

namespace epa::core {

namespace {

bool is_printable(std::uint32_t cp) {
  if (cp < 0x20 || cp == 0x7F || (cp >= 0x80 && cp <= 0x9F)) return false;  // C0 (ESC, newline, tab), DEL, C1
  if (cp == 0x2028 || cp == 0x2029) return false;                            // line and paragraph separators
  if ((cp >= 0x202A && cp <= 0x202E) || (cp >= 0x2066 && cp <= 0x2069)) return false;  // bidirectional overrides
  if (cp == 0x200E || cp == 0x200F || cp == 0xFEFF) return false;            // direction marks, BOM
  return true;
}

std::string hex_byte(unsigned char c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "\\x%02x", c);
  return buf;
}

// The rule, said once for every refusal.
std::string rule(bool name, std::size_t max_chars) {
  return std::string(name ? ": a name is 1 to " : ": it is at most ") + std::to_string(max_chars) +
         " printable characters on one line";
}

Status check_text(std::string_view text, std::string_view what, std::size_t max_chars, bool name) {
  const std::string subject(what);
  if (const auto bad = first_invalid_utf8(text))
    return invalid_argument(subject + " is not valid UTF-8 (byte " + std::to_string(*bad) + ")" + rule(name, max_chars));
  std::size_t chars = 0;
  bool blank = true;
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t at = i;
    const std::uint32_t cp = decode_utf8(text, i);
    if (!is_printable(cp) && !(cp == '\t' && !name))  // a tab forges nothing: free text may keep one
      return invalid_argument(subject + " '" + visible_text(text) + "' holds a control character (byte " + std::to_string(at) +
                              (cp < 0x100 ? ", " + hex_byte(static_cast<unsigned char>(cp)).substr(1) : std::string()) + ")" +
                              rule(name, max_chars));
    blank = blank && cp == ' ';
    ++chars;
  }
  if (chars > max_chars)
    return invalid_argument(subject + " is " + std::to_string(chars) + " characters long" + rule(name, max_chars));
  if (name && blank) return invalid_argument(subject + " is empty" + rule(name, max_chars));
  return ok();
}

}  // namespace

Status check_printable_name(std::string_view text, std::string_view what, std::size_t max_chars) {
  return check_text(text, what, max_chars, true);
}

Status check_printable_text(std::string_view text, std::string_view what, std::size_t max_chars) {
  return check_text(text, what, max_chars, false);
}

std::string visible_text(std::string_view text, std::size_t max_chars) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c >= 0x7F ? hex_byte(c) : std::string(1, static_cast<char>(c));
  }
  return text.size() > max_chars ? out + "..." : out;
}

}  // namespace epa::core
