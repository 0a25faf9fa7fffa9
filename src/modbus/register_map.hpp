#pragma once
// The register map (registers/*.csv, `epa-registers/1`): the single source of the Modbus
// interface. Each row binds a named point (points/point_catalog.hpp) to a table and address with a data
// type, word order, scale, unit, access, range, default and persistence. Loaded and validated at
// start-up; every error names the file, the line and what was expected.
//
//   name,table,address,type,word_order,scale,unit,access,min,max,default,persisted,description
//   setpoint_mm,holding,0,float32,ABCD,1,mm,rw,0,500,0,yes,position setpoint
//
// Required columns: name, table, address, type; the others may be absent or empty (defaults: word
// order ABCD, scale 1, the point's unit and description, access r, the point's range, no
// default, not persisted). Addresses are 0-based protocol addresses. For integer types the
// register holds round(value * scale); for float32, the value in IEEE-754 with the word order.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "core/word_order.hpp"
#include "points/point_catalog.hpp"
#include "points/write_limits.hpp"

namespace epa::modbus {

enum class Table : std::uint8_t { kCoil, kDiscreteInput, kInputRegister, kHoldingRegister };
// key64: the unlock key, 4 holding registers, most significant first; never read as a number.
enum class DataType : std::uint8_t { kBool, kUint16, kInt16, kUint32, kInt32, kFloat32, kKey64 };

std::string_view to_string(Table t);     // "coil", "discrete", "input", "holding"
std::string_view to_string(DataType t);  // "bool", "uint16", ...
bool is_bit_table(Table t);

struct RegisterEntry {
  const points::PointDef* point = nullptr;
  Table table = Table::kHoldingRegister;
  int address = 0;
  DataType type = DataType::kUint16;
  core::WordOrder word_order = core::WordOrder::kABCD;
  double scale = 1.0;
  std::string unit;
  bool writable = false;
  double min = 0.0, max = 0.0;  // engineering units; what a write may carry
  std::optional<double> default_value;
  bool persisted = false;
  std::string description;
  int line = 0;  // in the map file, for messages

  int width() const {
    if (type == DataType::kKey64) return 4;
    return type == DataType::kUint32 || type == DataType::kInt32 || type == DataType::kFloat32 ? 2 : 1;
  }
};

class RegisterMap {
 public:
  static core::Result<RegisterMap> parse(const std::string& text, const std::string& source);
  static core::Result<RegisterMap> load(const std::string& path);

  const std::vector<RegisterEntry>& entries() const { return entries_; }
  const std::string& source() const { return source_; }

  struct Hit {
    const RegisterEntry* entry = nullptr;
    int offset = 0;  // which register of a 32-bit value (0 or 1)
  };
  Hit find(Table table, int address) const noexcept;
  int end_address(Table table) const noexcept { return static_cast<int>(index_[static_cast<int>(table)].size()); }
  // Where reads of the table end: a bit table's end rounded up to a multiple of 16 (clients read
  // coils and discrete inputs 8 or 16 at a time; the padding reads 0), a register table's end.
  int readable_end(Table table) const noexcept {
    const int end = end_address(table);
    return is_bit_table(table) ? (end + kBitBlock - 1) / kBitBlock * kBitBlock : end;
  }
  static constexpr int kBitBlock = 16;

 private:
  std::string add(RegisterEntry e);  // what is wrong with where it goes (an overlap), "" when nothing

  std::string source_;
  std::vector<RegisterEntry> entries_;
  std::array<std::vector<std::int32_t>, 4> index_;  // per table: address -> entry index, -1 unmapped
};

// The map's ranges narrow the one set of write limits (every interface's), and its defaults must
// lie within them: a map that leaves a point no value, or whose default the configuration's limits
// exclude, is refused with the file, line and reason.
core::Status narrow_limits(const RegisterMap& map, points::WriteLimits& limits);

// Engineering value <-> register words (width() of them) or a bit. Integer types round and clamp
// to their range; a NaN ("never reached") becomes the type's sentinel: int16 -32768, uint16 65535,
// int32 INT32_MIN, uint32 UINT32_MAX (float32 carries the NaN itself).
void encode_value(const RegisterEntry& e, double value, std::uint16_t* words) noexcept;
double decode_value(const RegisterEntry& e, const std::uint16_t* words) noexcept;
// The 64-bit key of a key64's four words.
std::uint64_t key_value(const std::uint16_t* words) noexcept;

}  // namespace epa::modbus
