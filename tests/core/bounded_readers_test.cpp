// Every file reader is bounded: not a regular file or above its cap is refused before reading,
// names the file; JSON is strict (UTF-8, depth, duplicate keys); names are one printable line.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "../support/temp_path.hpp"
#include "../support/text_contains.hpp"
#include "core/coefficient_cap.hpp"
#include "core/model_file.hpp"
#include "core/printable_name.hpp"
#include "core/run_file.hpp"
#include "core/strict_json.hpp"
#include "core/text_file.hpp"
#include "core/tiny_number.hpp"
#include "core/utf8.hpp"

namespace epa::core {
namespace {

using epa::test::contains;
using epa::test::TempDir;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(TextFile, ReadsARegularFileWhole) {
  const TempDir dir("text");
  const auto path = (dir.path / "a.toml").string();
  std::ofstream(path) << "schema = 1\n";
  const auto text = read_text_file(path, "model file");
  ASSERT_TRUE(text.has_value()) << text.error().message;
  EXPECT_EQ(*text, "schema = 1\n");
}

TEST(TextFile, RefusesADeviceUnreadNamingTheFileAndItsRole) {
  const auto start = std::chrono::steady_clock::now();
  const auto text = read_text_file("/dev/zero", "model file");
  ASSERT_FALSE(text.has_value());
  EXPECT_EQ(text.error().message, "/dev/zero: not a regular file (character device): cannot read the model file");
  EXPECT_LT(seconds_since(start), 1.0);
}

TEST(TextFile, RefusesAFolderAndAFifoWithoutWaitingForAWriter) {
  const TempDir dir("text");
  const auto folder = read_text_file(dir.path.string(), "tuning file");
  ASSERT_FALSE(folder.has_value());
  EXPECT_TRUE(contains(folder.error().message, "not a regular file (folder)"));
  const auto fifo = (dir.path / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  const auto text = read_text_file(fifo, "tuning file");
  ASSERT_FALSE(text.has_value());
  EXPECT_TRUE(contains(text.error().message, fifo + ": not a regular file (FIFO)"));
  EXPECT_LT(seconds_since(start), 1.0);
}

TEST(TextFile, RefusesASparseGigabyteAtItsSize) {
  const TempDir dir("text");
  const auto path = (dir.path / "big.toml").string();
  std::ofstream{path};
  std::filesystem::resize_file(path, std::uintmax_t{1} << 30);  // sparse: no disk used
  const auto start = std::chrono::steady_clock::now();
  const auto text = read_text_file(path, "tuning file", 4 * kMiB);
  ASSERT_FALSE(text.has_value());
  EXPECT_EQ(text.error().message, path + ": 1073741824 bytes, above the 4 MiB cap for a tuning file");
  EXPECT_LT(seconds_since(start), 1.0);
}

TEST(TextFile, AMissingFileSaysWhy) {
  const auto text = read_text_file("/nonexistent-dir/m.toml", "model file");
  ASSERT_FALSE(text.has_value());
  EXPECT_EQ(text.error().message, "/nonexistent-dir/m.toml: cannot open the model file: No such file or directory");
}

TEST(TextFile, CapsAreSaidInWholeUnits) {
  EXPECT_EQ(byte_size_text(4 * kMiB), "4 MiB");
  EXPECT_EQ(byte_size_text(64 * 1024), "64 KiB");
  EXPECT_EQ(byte_size_text(1000), "1000 bytes");
}

TEST(RunFileBounds, ADeviceAndAnOversizedFileAreRefusedNamingThem) {
  const auto zero = read_run_file("/dev/zero");
  ASSERT_FALSE(zero.has_value());
  EXPECT_TRUE(contains(zero.error().message, "/dev/zero: not a regular file (character device): cannot read the run file"));
  const TempDir dir("run");
  const auto path = (dir.path / "big.csv").string();
  std::ofstream{path};
  std::filesystem::resize_file(path, std::uintmax_t{1} << 30);
  const auto big = read_run_file(path);
  ASSERT_FALSE(big.has_value());
  EXPECT_TRUE(contains(big.error().message, path + ": 1073741824 bytes, above the 160 MiB cap for a run file"));
}

TEST(RunFileBounds, AnOverlongLineIsRefusedNamingTheLine) {
  const TempDir dir("run");
  const auto path = (dir.path / "nul.csv").string();
  std::ofstream(path) << std::string(1 << 20, '\0');
  const auto run = read_run_file(path);
  ASSERT_FALSE(run.has_value());
  EXPECT_TRUE(contains(run.error().message, path + ":1: line longer than 4096 bytes"));
  EXPECT_LT(run.error().message.size(), 200u);  // the line itself is not quoted
}

TEST(CoefficientCap, AModelWithThousandsOfCoefficientsIsRefusedNamingTheKey) {
  std::string A = "[1.0";
  for (int i = 0; i < 100000; ++i) A += ", 0.0";
  const std::string text = "schema = \"epa-model/1\"\nTs = 0.005\n[arx]\nA = " + A + "]\nB = [0.0, 1.0]\n"
                           "[dead_zone]\nm_r = 1.0\nm_l = 1.0\nb_r = 1.0\nb_l = -1.0\n";
  const auto start = std::chrono::steady_clock::now();
  const auto model = parse_model_toml(text, "m.toml");
  ASSERT_FALSE(model.has_value());
  EXPECT_EQ(model.error().message, "m.toml: [arx] A has 100001 coefficients, more than the 64 a polynomial may have");
  EXPECT_LT(seconds_since(start), 2.0);
  EXPECT_TRUE(check_coefficient_count(64, "F").has_value());
}

TEST(StrictJson, ReadsAnOrdinaryDocument) {
  const auto j = parse_strict_json(R"({"F": [1, -1.5, 0.56], "name": "Wärme"})", "d.json");
  ASSERT_TRUE(j.has_value()) << j.error().message;
  EXPECT_EQ((*j)["F"].size(), 3u);
}

TEST(StrictJson, InvalidUtf8IsRefusedInOurWords) {
  const auto j = parse_strict_json("{\"name\": \"a\xff\xfe\"}", "the request body");
  ASSERT_FALSE(j.has_value());
  EXPECT_EQ(j.error().message, "the request body: not valid UTF-8 JSON (byte 11)");
  EXPECT_TRUE(first_invalid_utf8("\xed\xa0\x80").has_value());  // a surrogate
  EXPECT_TRUE(first_invalid_utf8("\xc0\xaf").has_value());                              // an overlong '/'
  EXPECT_FALSE(first_invalid_utf8("Wärme €").has_value());
}

TEST(StrictJson, DeepNestingEndsFastAtTheCap) {
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  const auto start = std::chrono::steady_clock::now();
  const auto j = parse_strict_json(deep, "deep.json");
  ASSERT_FALSE(j.has_value());
  EXPECT_EQ(j.error().message, "deep.json: nested deeper than 64 levels");
  EXPECT_LT(seconds_since(start), 1.0);
  EXPECT_TRUE(parse_strict_json(std::string(64, '[') + std::string(64, ']'), "ok").has_value());
  EXPECT_FALSE(parse_strict_json(std::string(65, '[') + std::string(65, ']'), "no").has_value());
}

TEST(StrictJson, ADuplicateKeyIsRefusedNamingIt) {
  const auto j = parse_strict_json(R"({"setpoint_mm": 10, "setpoint_mm": 400})", "the request body");
  ASSERT_FALSE(j.has_value());
  EXPECT_EQ(j.error().message, "the request body: duplicate key 'setpoint_mm' (each key may appear once)");
  // The same key in two objects is no duplicate.
  EXPECT_TRUE(parse_strict_json(R"({"a": {"k": 1}, "b": {"k": 2}, "k": 3})", "x").has_value());
}

TEST(StrictJson, ASyntaxErrorSaysWhere) {
  const auto j = parse_strict_json("{\n  \"a\": tru }", "spec.json");
  ASSERT_FALSE(j.has_value());
  EXPECT_TRUE(contains(j.error().message, "spec.json: not valid JSON: parse error at line 2"));
}

TEST(PrintableName, OneLineOfPrintableCharacters) {
  EXPECT_TRUE(check_printable_name("paper", "set name").has_value());
  EXPECT_TRUE(check_printable_name("Achse 2 (Wärme)", "set name").has_value());
  EXPECT_TRUE(check_printable_name(std::string(64, 'x'), "set name").has_value());
}

TEST(PrintableName, ControlCharactersLengthAndBlanksAreRefusedNamingTheRule) {
  const auto esc = check_printable_name("ok\x1b[2J", "set name");
  ASSERT_FALSE(esc.has_value());
  EXPECT_EQ(esc.error().message,
            "set name 'ok\\x1b[2J' holds a control character (byte 2, x1b): a name is 1 to 64 printable characters on one line");
  const auto newline = check_printable_name("a\nforged log line", "set name");
  ASSERT_FALSE(newline.has_value());
  EXPECT_TRUE(contains(newline.error().message, "holds a control character (byte 1"));
  EXPECT_FALSE(check_printable_name("a\xc2\x9b" "31m", "set name").has_value());       // C1 CSI
  EXPECT_FALSE(check_printable_name("a\xe2\x80\xae" "cba", "set name").has_value());   // right-to-left override
  const auto long_name = check_printable_name(std::string(1 << 20, 'x'), "set name");
  ASSERT_FALSE(long_name.has_value());
  EXPECT_TRUE(contains(long_name.error().message, "set name is 1048576 characters long"));
  EXPECT_FALSE(check_printable_name("", "set name").has_value());
  EXPECT_FALSE(check_printable_name("   ", "set name").has_value());
  EXPECT_FALSE(check_printable_name("a\xff", "set name").has_value());
  EXPECT_TRUE(check_printable_text("", "source", 1024).has_value());
}

TEST(TinyNumber, SubnormalFloatsAndUnderflowsAreTinyZeroIsNot) {
  EXPECT_TRUE(is_tiny_number(2.4e-41));   // 100.0 written as CDAB
  EXPECT_TRUE(is_tiny_number(-1e-300));
  EXPECT_TRUE(is_tiny_number(5e-324));
  EXPECT_FALSE(is_tiny_number(0.0));
  EXPECT_FALSE(is_tiny_number(1.2e-38));
  EXPECT_FALSE(is_tiny_number(120.0));
}

}  // namespace
}  // namespace epa::core
