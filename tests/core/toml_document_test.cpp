// What every TOML reader says of a file it cannot take: a syntax error at its file and line, a
// missing or foreign schema naming the one expected.
#include "core/toml_document.hpp"

#include <gtest/gtest.h>

namespace epa::core {
namespace {

TEST(TomlDocument, ASyntaxErrorNamesFileAndLine) {
  const auto r = parse_toml("a = 1\nb = = 2\n", "x.toml");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().code, ErrorCode::kParse);
  EXPECT_EQ(r.error().message.rfind("x.toml:2: ", 0), 0u) << r.error().message;
}

TEST(TomlDocument, TheSchemaMustBeTheOneTheReaderKnows) {
  const auto missing = parse_toml_with_schema("a = 1\n", "m.toml", "epa-model/1");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().message, "m.toml: schema is missing (expected \"epa-model/1\")");

  const auto other = parse_toml_with_schema("schema = \"epa-model/2\"\n", "m.toml", "epa-model/1");
  ASSERT_FALSE(other.has_value());
  EXPECT_EQ(other.error().message, "m.toml: schema \"epa-model/2\" is not supported (expected \"epa-model/1\")");

  const auto number = parse_toml_with_schema("schema = 1\n", "m.toml", "epa-model/1");
  ASSERT_FALSE(number.has_value());
  EXPECT_EQ(number.error().message, "m.toml:1: schema is not a string (expected \"epa-model/1\")");

  const auto good = parse_toml_with_schema("schema = \"epa-model/1\"\nTs = 0.005\n", "m.toml", "epa-model/1");
  ASSERT_TRUE(good.has_value()) << good.error().message;
  EXPECT_EQ((*good)["Ts"].value<double>(), 0.005);
}

}  // namespace
}  // namespace epa::core
