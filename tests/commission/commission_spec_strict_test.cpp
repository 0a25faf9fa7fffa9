// A commissioning spec is read strictly: invalid UTF-8 and duplicate keys are refused in plain words.
#include <gtest/gtest.h>

#include <string>

#include "commission/commission_spec.hpp"

namespace epa::commission {
namespace {

TEST(CommissionSpecStrict, InvalidUtf8IsRefusedWithoutTheBytes) {
  const auto s = parse_commission_spec("{\"name\": \"axis\xc3\x28\"}");
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error().message, "commission spec: not valid UTF-8 JSON (byte 14)");
}

TEST(CommissionSpecStrict, ADuplicateKeyIsRefusedNamingIt) {
  const auto s = parse_commission_spec(R"({"excitation_runs": 2, "limits": {"ess_mm": 1, "ess_mm": 50}})");
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error().message, "commission spec: duplicate key 'ess_mm' (each key may appear once)");
}

TEST(CommissionSpecStrict, DeepNestingIsRefused) {
  const auto s = parse_commission_spec("{\"moves_mm\": " + std::string(200000, '[') + std::string(200000, ']') + "}");
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error().message, "commission spec: nested deeper than 64 levels");
}

}  // namespace
}  // namespace epa::commission
