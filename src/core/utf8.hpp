#pragma once
// UTF-8 as the readers accept it: well-formed (no overlong forms, no surrogates, nothing above
// U+10FFFF), so text that reaches a JSON answer, the log or the store can always be written out.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace epa::core {

// The offset of the first byte that does not start or continue a well-formed sequence, or nullopt.
std::optional<std::size_t> first_invalid_utf8(std::string_view text);

// The code points of well-formed `text`, one at a time: decode_utf8(text, i) reads the one at byte
// i and moves i past it. Only for text first_invalid_utf8 accepted.
std::uint32_t decode_utf8(std::string_view text, std::size_t& i);

}  // namespace epa::core
