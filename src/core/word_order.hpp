#pragma once
// 32-bit values in two 16-bit Modbus registers, with the word and byte order named the way
// integrators name it: ABCD (big-endian, the default), CDAB (word swap), BADC (byte swap),
// DCBA (both). Our own code, pinned by test vectors, because libmodbus' float helpers changed
// behaviour across versions. A is the most significant byte of the IEEE-754 / two's-complement value.
#include <array>
#include <bit>
#include <cstdint>
#include <string_view>

#include "core/result.hpp"

namespace epa::core {

enum class WordOrder { kABCD, kCDAB, kBADC, kDCBA };

std::string_view to_string(WordOrder order);
Result<WordOrder> parse_word_order(std::string_view text);  // "ABCD", "CDAB", "BADC", "DCBA"

// registers[0] is the lower address.
constexpr std::array<std::uint16_t, 2> encode_u32(std::uint32_t v, WordOrder order) {
  const auto hi = static_cast<std::uint16_t>(v >> 16), lo = static_cast<std::uint16_t>(v & 0xFFFF);
  auto swap = [](std::uint16_t w) { return static_cast<std::uint16_t>((w << 8) | (w >> 8)); };
  switch (order) {
    case WordOrder::kABCD: return {hi, lo};
    case WordOrder::kCDAB: return {lo, hi};
    case WordOrder::kBADC: return {swap(hi), swap(lo)};
    case WordOrder::kDCBA: return {swap(lo), swap(hi)};
  }
  return {hi, lo};
}

constexpr std::uint32_t decode_u32(std::array<std::uint16_t, 2> r, WordOrder order) {
  // Every order is its own inverse on the register pair, so decoding re-encodes.
  const auto abcd = encode_u32((static_cast<std::uint32_t>(r[0]) << 16) | r[1], order);
  return (static_cast<std::uint32_t>(abcd[0]) << 16) | abcd[1];
}

constexpr std::array<std::uint16_t, 2> encode_f32(float v, WordOrder o) { return encode_u32(std::bit_cast<std::uint32_t>(v), o); }
constexpr float decode_f32(std::array<std::uint16_t, 2> r, WordOrder o) { return std::bit_cast<float>(decode_u32(r, o)); }
constexpr std::array<std::uint16_t, 2> encode_i32(std::int32_t v, WordOrder o) { return encode_u32(std::bit_cast<std::uint32_t>(v), o); }
constexpr std::int32_t decode_i32(std::array<std::uint16_t, 2> r, WordOrder o) { return std::bit_cast<std::int32_t>(decode_u32(r, o)); }

}  // namespace epa::core
