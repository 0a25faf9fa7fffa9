#include "core/utf8.hpp"

namespace epa::core {

namespace {

// The length of the sequence that starts with `lead`, 0 when no sequence starts with it.
std::size_t sequence_length(unsigned char lead) {
  if (lead < 0x80) return 1;
  if (lead >= 0xC2 && lead <= 0xDF) return 2;
  if (lead >= 0xE0 && lead <= 0xEF) return 3;
  if (lead >= 0xF0 && lead <= 0xF4) return 4;
  return 0;  // a continuation byte, C0/C1 (overlong) or F5..FF (beyond U+10FFFF)
}

bool is_continuation(unsigned char c) { return (c & 0xC0) == 0x80; }

}  // namespace

std::optional<std::size_t> first_invalid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const auto lead = static_cast<unsigned char>(text[i]);
    const std::size_t n = sequence_length(lead);
    if (n == 0 || i + n > text.size()) return i;
    for (std::size_t k = 1; k < n; ++k)
      if (!is_continuation(static_cast<unsigned char>(text[i + k]))) return i;
    const auto second = static_cast<unsigned char>(text[i + 1 < text.size() ? i + 1 : i]);
    if (lead == 0xE0 && second < 0xA0) return i;   // overlong three-byte form
    if (lead == 0xED && second >= 0xA0) return i;  // UTF-16 surrogates
    if (lead == 0xF0 && second < 0x90) return i;   // overlong four-byte form
    if (lead == 0xF4 && second >= 0x90) return i;  // above U+10FFFF
    i += n;
  }
  return std::nullopt;
}

std::uint32_t decode_utf8(std::string_view text, std::size_t& i) {
  const auto lead = static_cast<unsigned char>(text[i]);
  const std::size_t n = sequence_length(lead);
  if (n <= 1 || i + n > text.size()) return text[i++] & 0xFFu;
  static constexpr unsigned char kLeadMask[] = {0, 0, 0x1F, 0x0F, 0x07};
  std::uint32_t cp = lead & kLeadMask[n];
  for (std::size_t k = 1; k < n; ++k) cp = (cp << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3Fu);
  i += n;
  return cp;
}

}  // namespace epa::core
