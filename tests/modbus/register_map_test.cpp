#include "modbus/register_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "modbus/register_export.hpp"

namespace epa::modbus {
namespace {

const std::string kHeader = "name,table,address,type,word_order,scale,unit,access,min,max,default,persisted,description\n";

std::string error_of(const std::string& rows) {
  auto m = RegisterMap::parse(kHeader + rows, "map.csv");
  return m.has_value() ? "(accepted)" : m.error().message;
}

TEST(RegisterMap, ShippedMapAndTheLegacyExampleAreValid) {
  for (const char* f : {"/registers/epa.csv", "/registers/examples/legacy-hmi.csv"}) {
    auto m = RegisterMap::load(std::string(EPA_SOURCE_DIR) + f);
    ASSERT_TRUE(m.has_value()) << m.error().message;
    EXPECT_GT(m->entries().size(), 5u);
  }
}

TEST(RegisterMap, FindsEachRegisterOfAThirtyTwoBitValue) {
  auto m = RegisterMap::parse(kHeader + "setpoint_mm,holding,10,float32,CDAB,,,rw,0,500,,yes,\n", "m.csv");
  ASSERT_TRUE(m.has_value()) << m.error().message;
  EXPECT_EQ(m->find(Table::kHoldingRegister, 10).offset, 0);
  EXPECT_EQ(m->find(Table::kHoldingRegister, 11).offset, 1);
  EXPECT_EQ(m->find(Table::kHoldingRegister, 11).entry->point->name, "setpoint_mm");
  EXPECT_EQ(m->find(Table::kHoldingRegister, 12).entry, nullptr);
  EXPECT_EQ(m->find(Table::kInputRegister, 10).entry, nullptr);
  EXPECT_EQ(m->end_address(Table::kHoldingRegister), 12);
}

TEST(RegisterMap, EachBadRowIsRefusedWithFileLineAndReason) {
  EXPECT_NE(error_of("position_mm,input,0,float32,,,,r,,,,,\nerror_mm,input,1,float32,,,,r,,,,,\n").find("map.csv:3: input address 1 overlaps 'position_mm' of line 2"),
            std::string::npos);
  EXPECT_NE(error_of("position_mm,coil,0,float32,,,,r,,,,,\n").find("map.csv:2: type float32 does not fit the coil table"), std::string::npos);
  EXPECT_NE(error_of("fault_active,holding,0,bool,,,,r,,,,,\n").find("does not fit the holding table"), std::string::npos);
  EXPECT_NE(error_of("positoin_mm,input,0,float32,,,,r,,,,,\n").find("unknown point 'positoin_mm'"), std::string::npos);
  EXPECT_NE(error_of("setpoint_mm,holding,0,float32,,,,rw,0,500,600,no,\n").find("default 600 lies outside [0, 500]"), std::string::npos);
  EXPECT_NE(error_of("setpoint_mm,holding,0,float32,,,,rw,0,500\n").find("expected 13 fields"), std::string::npos);
  EXPECT_NE(error_of("position_mm,holding,0,float32,,,,rw,,,,,\n").find("read-only: access must be r"), std::string::npos);
  EXPECT_NE(error_of("setpoint_mm,input,0,float32,,,,rw,,,,,\n").find("Modbus cannot write it"), std::string::npos);
  EXPECT_NE(error_of("setpoint_mm,holding,0,int16,,100,,rw,0,500,,,\n").find("does not fit a int16 with scale 100"), std::string::npos);
  EXPECT_NE(error_of("setpoint_mm,holding,0,float32,,,,rw,0,900,,,\n").find("goes beyond what 'setpoint_mm' accepts"), std::string::npos);
  EXPECT_NE(error_of("setpoint_mm,holding,65535,float32,,,,rw,,,,,\n").find("runs past 65535"), std::string::npos);
  EXPECT_NE(error_of("mode,holding,0,uint16,ABCD,,,rw,,,,,\n").find("word_order applies to 32-bit types only"), std::string::npos);
  EXPECT_NE(error_of("position_mm,input,x,float32,,,,r,,,,,\n").find("address 'x'"), std::string::npos);
  EXPECT_NE(error_of("position_mm,input,0,float32,,,,r,,,,yes,\n").find("only writable (rw) points can be persisted"), std::string::npos);
  EXPECT_NE(error_of("").find("maps no points"), std::string::npos);
}

TEST(RegisterMap, UnknownColumnAndMissingColumnAreRefused) {
  auto m = RegisterMap::parse("name,table,adress,type\n", "m.csv");
  ASSERT_FALSE(m.has_value());
  EXPECT_NE(m.error().message.find("missing column 'address'"), std::string::npos) << m.error().message;
}

// Found by fuzz_register_map: with a column named twice the row was checked against the number of
// distinct names, and the second name's index read past the end of a row that short.
TEST(RegisterMap, ASpreadsheetsByteOrderMarkAndCrLfLineEndsAreRead) {
  // Excel's "CSV UTF-8" and Windows line ends: the same map as the plain file.
  const std::string plain = "name,table,address,type\nsetpoint_mm,holding,0,float32\nmode,holding,2,uint16\n";
  std::string excel = "\xEF\xBB\xBF";
  for (char ch : plain) excel += ch == '\n' ? std::string("\r\n") : std::string(1, ch);
  auto a = RegisterMap::parse(plain, "plain.csv");
  auto b = RegisterMap::parse(excel, "excel.csv");
  ASSERT_TRUE(a.has_value()) << a.error().message;
  ASSERT_TRUE(b.has_value()) << b.error().message;
  ASSERT_EQ(b->entries().size(), a->entries().size());
  for (std::size_t i = 0; i < a->entries().size(); ++i) {
    EXPECT_EQ(b->entries()[i].point, a->entries()[i].point);
    EXPECT_EQ(b->entries()[i].address, a->entries()[i].address);
    EXPECT_EQ(b->entries()[i].type, a->entries()[i].type);
  }
}

TEST(RegisterMap, ANulByteIsRefusedNamingLineAndColumn) {
  const std::string text = std::string("name,table,address,type\nsetpoint_mm,hol") + '\0' + "ding,0,float32\n";
  auto m = RegisterMap::parse(text, "nul.csv");
  ASSERT_FALSE(m.has_value());
  EXPECT_NE(m.error().message.find("nul.csv:2: column 16"), std::string::npos) << m.error().message;
  EXPECT_NE(m.error().message.find("NUL"), std::string::npos) << m.error().message;
}

TEST(RegisterMap, ARepeatedColumnIsRefused) {
  auto m = RegisterMap::parse("name,table,address,type,min,min,max\nsetpoint_mm,holding,0,float32,0,500\n", "m.csv");
  ASSERT_FALSE(m.has_value());
  EXPECT_NE(m.error().message.find("m.csv:1: header: column 'min' appears twice"), std::string::npos) << m.error().message;
}

TEST(RegisterMap, QuotedDescriptionsMayHoldCommas) {
  auto m = RegisterMap::parse(kHeader + "position_mm,input,0,float32,,,mm,r,,,,no,\"position, measured\"\n", "m.csv");
  ASSERT_TRUE(m.has_value()) << m.error().message;
  EXPECT_EQ(m->entries()[0].description, "position, measured");
}

RegisterEntry entry(DataType t, double scale = 1.0, core::WordOrder o = core::WordOrder::kABCD) {
  RegisterEntry e;
  e.type = t;
  e.scale = scale;
  e.word_order = o;
  return e;
}

// Values worked out by hand: 123.5f = 0x42F70000; 12.34 mm at scale 10 = 123 = 0x007B;
// -1.5 at int16 scale 100 = -150 = 0xFF6A.
TEST(RegisterCodec, EncodesByTypeScaleAndWordOrder) {
  std::uint16_t w[2] = {};
  encode_value(entry(DataType::kFloat32), 123.5, w);
  EXPECT_EQ(w[0], 0x42F7);
  EXPECT_EQ(w[1], 0x0000);
  encode_value(entry(DataType::kFloat32, 1, core::WordOrder::kCDAB), 123.5, w);
  EXPECT_EQ(w[0], 0x0000);
  EXPECT_EQ(w[1], 0x42F7);
  encode_value(entry(DataType::kUint16, 10), 12.34, w);
  EXPECT_EQ(w[0], 0x007B);
  encode_value(entry(DataType::kInt16, 100), -1.5, w);
  EXPECT_EQ(w[0], 0xFF6A);
  EXPECT_DOUBLE_EQ(decode_value(entry(DataType::kInt16, 100), w), -1.5);
  encode_value(entry(DataType::kUint32), 70000, w);
  EXPECT_EQ(w[0], 0x0001);
  EXPECT_EQ(w[1], 0x1170);
}

TEST(RegisterCodec, NeverReachedBecomesTheTypesSentinelAndValuesClamp) {
  std::uint16_t w[2] = {};
  encode_value(entry(DataType::kInt16), std::nan(""), w);
  EXPECT_EQ(w[0], 0x8000);
  encode_value(entry(DataType::kUint16), std::nan(""), w);
  EXPECT_EQ(w[0], 0xFFFF);
  encode_value(entry(DataType::kInt16, 10), 5000.0, w);  // 50000 does not fit: clamps to 32767
  EXPECT_EQ(w[0], 32767);
  encode_value(entry(DataType::kFloat32), std::nan(""), w);
  EXPECT_TRUE(std::isnan(decode_value(entry(DataType::kFloat32), w)));
}

TEST(RegisterExport, ReferencesAreOneBasedWithTheTablesPrefix) {
  EXPECT_EQ(reference_alias(Table::kHoldingRegister, 0), "40001");
  EXPECT_EQ(reference_alias(Table::kInputRegister, 9), "30010");
  EXPECT_EQ(reference_alias(Table::kCoil, 0), "00001");
  EXPECT_EQ(reference_alias(Table::kDiscreteInput, 3), "10004");
  EXPECT_EQ(reference_alias(Table::kHoldingRegister, 10000), "410001");
}

TEST(RegisterExport, MarkdownAndCsvListEveryEntry) {
  auto m = RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");
  ASSERT_TRUE(m.has_value());
  const auto md = export_markdown(*m), csv = export_csv(*m);
  EXPECT_NE(md.find("| setpoint_mm | holding | 0-1 | 40001 | float32 | ABCD |"), std::string::npos) << md.substr(0, 800);
  EXPECT_NE(csv.find("setpoint_mm,holding,0,40001,float32,ABCD,1,mm,rw,no,0,500,0,yes,"), std::string::npos) << csv.substr(0, 400);
  EXPECT_NE(csv.find("record1_target_mm,holding,1000,41001,float32,ABCD,1,mm,rw,yes,"), std::string::npos) << "the unlock is said";
  const auto lines = std::count(csv.begin(), csv.end(), '\n');
  EXPECT_EQ(static_cast<std::size_t>(lines), m->entries().size() + 1);
}

// Every row of every Markdown table has as many cells as its header: a "|" inside a description
// (|target - position|) is escaped, or it would split the cell.
TEST(RegisterExport, EveryTableRowHasItsHeadersCells) {
  auto m = RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");
  ASSERT_TRUE(m.has_value());
  std::istringstream md(export_markdown(*m));
  auto cells = [](const std::string& line) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < line.size(); ++i) n += line[i] == '|' && (i == 0 || line[i - 1] != '\\');
    return n;
  };
  std::size_t header = 0, rows = 0;
  for (std::string line; std::getline(md, line);) {
    const auto start = line.find_first_not_of(' ');
    if (start == std::string::npos || line[start] != '|') {
      header = 0;
      continue;
    }
    if (header == 0) {
      header = cells(line);
      continue;
    }
    ++rows;
    EXPECT_EQ(cells(line), header) << line;
  }
  EXPECT_GT(rows, m->entries().size());
}

// The guide names this map's addresses: the shipped map's words and bits where they are, a map
// without them says so instead of naming addresses it does not serve.
TEST(RegisterExport, TheGuideNamesTheMapsOwnAddresses) {
  auto shipped = RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");
  ASSERT_TRUE(shipped.has_value());
  const auto md = export_markdown(*shipped);
  EXPECT_NE(md.find("The control word is holding register 50 / 40051"), std::string::npos);
  EXPECT_NE(md.find("| 0 | 0x1 | start | 16 (00017) |"), std::string::npos);
  EXPECT_NE(md.find("| 8 | 0x100 | ack | 24 (10025) |"), std::string::npos);
  EXPECT_NE(md.find("record N (1..32) starts at holding register 1000 + 8·(N-1)"), std::string::npos);
  EXPECT_NE(md.find("`mbpoll -m tcp -a 1 -0 -1 -B -t 3:float -r 0 HOST`"), std::string::npos);

  auto small = RegisterMap::parse(kHeader + "position_mm,input,7,float32,ABCD,,mm,r,,,,no,\n"
                                            "setpoint_mm,holding,3,float32,ABCD,,mm,rw,0,500,,yes,\n", "small.csv");
  ASSERT_TRUE(small.has_value()) << small.error().message;
  const auto guide = export_markdown(*small);
  EXPECT_NE(guide.find("This map leaves out `mode`, `status_word`, `control_word`"), std::string::npos) << guide.substr(0, 1500);
  EXPECT_NE(guide.find("This map has neither word nor their bits."), std::string::npos);
  EXPECT_NE(guide.find("This map has no position records"), std::string::npos);
  EXPECT_EQ(guide.find("holding register 50"), std::string::npos);
}

// docs/registers.md is what integrators read: it must be the export of the shipped map.
TEST(RegisterExport, ShippedDocumentationIsTheExportOfTheShippedMap) {
  auto m = RegisterMap::load(std::string(EPA_SOURCE_DIR) + "/registers/epa.csv");
  ASSERT_TRUE(m.has_value());
  std::ifstream in(std::string(EPA_SOURCE_DIR) + "/docs/registers.md");
  std::stringstream doc;
  doc << in.rdbuf();
  std::string expected = export_markdown(*m);
  expected.replace(expected.find(m->source()), m->source().size(), "registers/epa.csv");
  EXPECT_EQ(doc.str(), expected) << "regenerate: build/release/src/app/epa registers registers/epa.csv --markdown docs/registers.md";
}

}  // namespace
}  // namespace epa::modbus
