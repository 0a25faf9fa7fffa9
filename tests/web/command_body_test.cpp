// The HTTP command bodies are read strictly: valid UTF-8, each key once, no value Modbus refuses.
#include <gtest/gtest.h>

#include <string>

#include "../support/text_contains.hpp"
#include "web/command_body.hpp"

namespace epa::web {
namespace {

using epa::test::contains;

TEST(CommandBody, AnOrdinarySetpointIsOneWrite) {
  const auto b = parse_command_body(CommandEndpoint::kSetpoint, R"({"setpoint_mm": 120})");
  ASSERT_EQ(b.error, "");
  ASSERT_EQ(b.writes.size(), 1u);
  EXPECT_EQ(b.writes[0].value, 120.0);
}

TEST(CommandBody, InvalidUtf8IsAPlainMalformedBody) {
  const auto b = parse_command_body(CommandEndpoint::kPoints, "{\"setpoint_mm\": 1, \"\xff\xfe\": 2}");
  EXPECT_EQ(b.error, "the request body: not valid UTF-8 JSON (byte 20)");
  EXPECT_TRUE(b.writes.empty());
}

TEST(CommandBody, ADuplicateKeyIsRefusedNamingIt) {
  for (const auto endpoint : {CommandEndpoint::kSetpoint, CommandEndpoint::kPoints}) {
    const auto b = parse_command_body(endpoint, R"({"setpoint_mm": 10, "setpoint_mm": 400})");
    EXPECT_TRUE(contains(b.error, "duplicate key 'setpoint_mm'"));
    EXPECT_TRUE(b.writes.empty());
  }
}

TEST(CommandBody, SubnormalAndHugeSetpointsAreRefusedAsModbusRefusesThem) {
  for (const char* value : {"2.4e-41", "5e-324", "-1e-300"}) {
    const auto b = parse_command_body(CommandEndpoint::kSetpoint, std::string("{\"setpoint_mm\": ") + value + "}");
    EXPECT_TRUE(contains(b.error, "setpoint_mm")) << value;
    EXPECT_TRUE(contains(b.error, "is not a usable number")) << value;
    EXPECT_TRUE(b.writes.empty()) << value;
  }
  const auto huge = parse_command_body(CommandEndpoint::kSetpoint, R"({"setpoint_mm": 1e999})");
  EXPECT_EQ(huge.error, "the request body: a number is beyond the range of a double");
  EXPECT_TRUE(huge.writes.empty());
  EXPECT_EQ(parse_command_body(CommandEndpoint::kSetpoint, R"({"setpoint_mm": 0})").error, "");
}

TEST(CommandBody, DeepNestingIsRefusedFast) {
  const auto b = parse_command_body(CommandEndpoint::kPoints, "{\"a\": " + std::string(100000, '[') + std::string(100000, ']') + "}");
  EXPECT_EQ(b.error, "the request body: nested deeper than 64 levels");
}

}  // namespace
}  // namespace epa::web
