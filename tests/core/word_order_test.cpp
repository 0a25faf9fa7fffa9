#include "core/word_order.hpp"

#include <gtest/gtest.h>

namespace epa::core {
namespace {

using Regs = std::array<std::uint16_t, 2>;

// Test vector from the Modbus issue: 123456.0f is 0x47F12000 in IEEE-754.
TEST(WordOrder, Float123456InEachOrder) {
  EXPECT_EQ(encode_f32(123456.0f, WordOrder::kABCD), (Regs{0x47F1, 0x2000}));
  EXPECT_EQ(encode_f32(123456.0f, WordOrder::kCDAB), (Regs{0x2000, 0x47F1}));
  EXPECT_EQ(encode_f32(123456.0f, WordOrder::kBADC), (Regs{0xF147, 0x0020}));
  EXPECT_EQ(encode_f32(123456.0f, WordOrder::kDCBA), (Regs{0x0020, 0xF147}));
  EXPECT_EQ(decode_f32({0x47F1, 0x2000}, WordOrder::kABCD), 123456.0f);
  EXPECT_EQ(decode_f32({0x2000, 0x47F1}, WordOrder::kCDAB), 123456.0f);
}

// -1.5f = 0xBFC00000; -2 as int32 = 0xFFFFFFFE.
TEST(WordOrder, NegativeValuesRoundTripInEveryOrder) {
  for (WordOrder o : {WordOrder::kABCD, WordOrder::kCDAB, WordOrder::kBADC, WordOrder::kDCBA}) {
    EXPECT_EQ(decode_f32(encode_f32(-1.5f, o), o), -1.5f) << to_string(o);
    EXPECT_EQ(decode_i32(encode_i32(-2, o), o), -2) << to_string(o);
    EXPECT_EQ(decode_u32(encode_u32(0x01020304u, o), o), 0x01020304u) << to_string(o);
  }
  EXPECT_EQ(encode_f32(-1.5f, WordOrder::kABCD), (Regs{0xBFC0, 0x0000}));
  EXPECT_EQ(encode_u32(0x01020304u, WordOrder::kDCBA), (Regs{0x0403, 0x0201}));
}

TEST(WordOrder, NamesParseAndUnknownIsRefused) {
  EXPECT_EQ(*parse_word_order("CDAB"), WordOrder::kCDAB);
  auto bad = parse_word_order("ACBD");
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("ACBD"), std::string::npos);
}

}  // namespace
}  // namespace epa::core
