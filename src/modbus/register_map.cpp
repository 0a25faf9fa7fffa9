#include "modbus/register_map.hpp"

#include "core/text_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "core/format.hpp"

#include <fmt/format.h>

namespace epa::modbus {

namespace {

constexpr std::pair<Table, std::string_view> kTables[] = {
    {Table::kCoil, "coil"}, {Table::kDiscreteInput, "discrete"}, {Table::kInputRegister, "input"}, {Table::kHoldingRegister, "holding"}};
constexpr std::pair<DataType, std::string_view> kTypes[] = {{DataType::kBool, "bool"},   {DataType::kUint16, "uint16"},
                                                             {DataType::kInt16, "int16"}, {DataType::kUint32, "uint32"},
                                                             {DataType::kInt32, "int32"}, {DataType::kFloat32, "float32"},
                                                             {DataType::kKey64, "key64"}};

std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// CSV fields; double quotes protect commas ("" is a quote inside them).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') fields.back() += '"', ++i;
      else if (c == '"') quoted = false;
      else fields.back() += c;
    } else if (c == '"') quoted = true;
    else if (c == ',') fields.emplace_back();
    else fields.back() += c;
  }
  for (auto& f : fields) f = trim(f);
  return fields;
}

std::optional<double> number(const std::string& s) {
  double v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

// What a write to a register of this type can carry, in engineering units after scaling (the
// sentinels only stand for "no value" when a NaN is read).
std::pair<double, double> representable(DataType t, double scale) {
  switch (t) {
    case DataType::kBool: return {0, 1};
    case DataType::kUint16: return {0, 65535 / scale};
    case DataType::kInt16: return {-32768 / scale, 32767 / scale};
    case DataType::kUint32: return {0, 4294967295.0 / scale};
    case DataType::kInt32: return {-2147483648.0 / scale, 2147483647.0 / scale};
    case DataType::kFloat32: return {-3.4e38, 3.4e38};
    case DataType::kKey64: return {0, 0};  // a key, never a number
  }
  return {0, 0};
}

}  // namespace

std::string_view to_string(Table t) {
  for (const auto& [v, n] : kTables) if (v == t) return n;
  return "?";
}
std::string_view to_string(DataType t) {
  for (const auto& [v, n] : kTypes) if (v == t) return n;
  return "?";
}
bool is_bit_table(Table t) { return t == Table::kCoil || t == Table::kDiscreteInput; }

core::Result<RegisterMap> RegisterMap::load(const std::string& path) {
  auto text = core::read_text_file(path, "register map", core::kSmallFileCapBytes);
  if (!text) return text.error();
  return parse(*text, path);
}

namespace {

using Columns = std::map<std::string, int>;  // header name -> index

// One data row, read by column name ("" for a column the header has not).
struct Row {
  const Columns& columns;
  const std::vector<std::string>& fields;
  std::string operator()(const char* c) const {
    const auto it = columns.find(c);
    return it == columns.end() ? std::string() : fields[static_cast<std::size_t>(it->second)];
  }
  bool has(const char* c) const { return columns.count(c) != 0; }
};

// Each step below reads part of a line and answers what is wrong with it, "" when nothing is.

// Spreadsheets save "CSV UTF-8" with a byte-order mark, and Windows ends lines with CR LF.
std::string clean_line(std::string& raw, int line_no) {
  if (line_no == 1 && raw.rfind("\xEF\xBB\xBF", 0) == 0) raw.erase(0, 3);
  if (!raw.empty() && raw.back() == '\r') raw.pop_back();
  if (const auto nul = raw.find('\0'); nul != std::string::npos)
    return fmt::format("column {}: a NUL byte (the file is not text: save it as CSV)", nul + 1);
  return "";
}

std::string read_header(const std::vector<std::string>& f, Columns& columns) {
  for (std::size_t i = 0; i < f.size(); ++i)  // a repeated name would leave an index past the row's fields
    if (!columns.emplace(f[i], static_cast<int>(i)).second) return fmt::format("header: column '{}' appears twice", f[i]);
  for (const char* required : {"name", "table", "address", "type"})
    if (!columns.count(required)) return fmt::format("header: missing column '{}'", required);
  static const std::vector<std::string> kKnown = {"name", "table", "address", "type", "word_order", "scale", "unit",
                                                  "access", "min", "max", "default", "persisted", "description"};
  for (const auto& [name, i] : columns)
    if (std::find(kKnown.begin(), kKnown.end(), name) == kKnown.end()) return fmt::format("header: unknown column '{}'", name);
  return "";
}

// The point, and where and as what the map puts it: table, address, type.
std::string read_place(const Row& get, RegisterEntry& e) {
  e.point = points::find_point(get("name"));
  if (!e.point) return fmt::format("unknown point '{}' (epa registers --points lists the points)", get("name"));
  const auto table = std::find_if(std::begin(kTables), std::end(kTables), [&](auto& t) { return t.second == get("table"); });
  if (table == std::end(kTables)) return fmt::format("table '{}' is not one of coil, discrete, input, holding", get("table"));
  e.table = table->first;
  const auto address = number(get("address"));
  if (!address || *address != std::floor(*address) || *address < 0 || *address > 65535)
    return fmt::format("address '{}' is not a whole number within 0..65535", get("address"));
  e.address = static_cast<int>(*address);
  const auto type = std::find_if(std::begin(kTypes), std::end(kTypes), [&](auto& t) { return t.second == get("type"); });
  if (type == std::end(kTypes)) return fmt::format("type '{}' is not one of bool, uint16, int16, uint32, int32, float32, key64", get("type"));
  e.type = type->first;
  const bool key_point = e.point->access == points::Access::kKey;
  if (key_point != (e.type == DataType::kKey64))
    return key_point ? fmt::format("'{}' is a 64-bit key: its type must be key64 (4 holding registers, most significant first)", e.point->name)
                     : "key64 is the type of the unlock key only";
  if (e.type == DataType::kKey64 && e.table != Table::kHoldingRegister) return "a key64 lives in the holding table";
  if (is_bit_table(e.table) != (e.type == DataType::kBool))
    return fmt::format("type {} does not fit the {} table (bool goes in coils and discrete inputs, numbers in input and holding registers)",
                       to_string(e.type), to_string(e.table));
  if (e.address + e.width() > 65536) return fmt::format("a {} at address {} runs past 65535", to_string(e.type), e.address);
  return "";
}

// How the value is encoded: word order and scale.
std::string read_encoding(const Row& get, RegisterEntry& e) {
  if (const auto wo = get("word_order"); !wo.empty()) {
    auto order = core::parse_word_order(wo);
    if (!order) return order.error().message;
    if (e.width() != 2) return "word_order applies to 32-bit types only (a key64 is most significant first)";
    e.word_order = *order;
  }
  if (const auto sc = get("scale"); !sc.empty()) {
    const auto v = number(sc);
    if (!v || *v <= 0) return fmt::format("scale '{}' must be a number > 0", sc);
    if ((e.type == DataType::kFloat32 || e.type == DataType::kBool) && *v != 1) return "scale applies to integer types only";
    e.scale = *v;
  }
  return "";
}

// Access, and the unit and description (the point's own unless the map says otherwise).
std::string read_access(const Row& get, RegisterEntry& e) {
  const auto access = get("access");
  if (access != "" && access != "r" && access != "rw") return fmt::format("access '{}' is not r or rw", access);
  e.writable = access == "rw";
  if (e.writable && (e.table == Table::kInputRegister || e.table == Table::kDiscreteInput))
    return fmt::format("access rw in the {} table: Modbus cannot write it (use holding or coil)", to_string(e.table));
  if (e.writable && !e.point->writable()) return fmt::format("point '{}' is read-only: access must be r", e.point->name);
  e.unit = get.has("unit") && !get("unit").empty() ? get("unit") : std::string(e.point->unit);
  e.description = get.has("description") && !get("description").empty() ? get("description") : std::string(e.point->description);
  return "";
}

// Range: the point's own, narrowed by the map's; it must be representable by the type. Then the
// default, within it.
std::string read_range(const Row& get, RegisterEntry& e) {
  using core::format_number;
  const auto [type_lo, type_hi] = representable(e.type, e.scale);
  e.min = e.point->writable() ? e.point->min : type_lo;
  e.max = e.point->writable() ? e.point->max : type_hi;
  for (const char* c : {"min", "max"}) {
    const auto s = get(c);
    if (s.empty()) continue;
    const auto v = number(s);
    if (!v) return fmt::format("{} '{}' is not a number", c, s);
    (c[1] == 'i' ? e.min : e.max) = *v;
  }
  if (e.min > e.max) return fmt::format("min {} exceeds max {}", format_number(e.min), format_number(e.max));
  if (e.type == DataType::kKey64) e.min = e.max = 0;  // not a number: the handler takes its words
  else if (e.writable && (e.min < type_lo || e.max > type_hi))
    return fmt::format("range [{}, {}] does not fit a {} with scale {} ([{}, {}])", format_number(e.min), format_number(e.max),
                       to_string(e.type), format_number(e.scale), format_number(type_lo), format_number(type_hi));
  if (e.writable && e.type != DataType::kKey64 && (e.min < e.point->min || e.max > e.point->max))
    return fmt::format("range [{}, {}] goes beyond what '{}' accepts ([{}, {}])", format_number(e.min), format_number(e.max), e.point->name,
                       format_number(e.point->min), format_number(e.point->max));
  if (const auto d = get("default"); !d.empty()) {
    const auto v = number(d);
    if (!v) return fmt::format("default '{}' is not a number", d);
    if (*v < e.min || *v > e.max) return fmt::format("default {} lies outside [{}, {}]", d, format_number(e.min), format_number(e.max));
    e.default_value = *v;
  }
  return "";
}

std::string read_persisted(const Row& get, RegisterEntry& e) {
  const auto persisted = get("persisted");
  if (persisted != "" && persisted != "yes" && persisted != "no") return fmt::format("persisted '{}' is not yes or no", persisted);
  e.persisted = persisted == "yes";
  if (e.persisted && !e.writable) return "only writable (rw) points can be persisted";
  return "";
}

std::string read_entry(const Row& row, RegisterEntry& e) {
  for (auto step : {read_place, read_encoding, read_access, read_range, read_persisted})
    if (std::string why = step(row, e); !why.empty()) return why;
  return "";
}

}  // namespace

core::Result<RegisterMap> RegisterMap::parse(const std::string& text, const std::string& src) {
  RegisterMap map;
  map.source_ = src;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  Columns columns;
  auto fail = [&](const std::string& why) { return core::parse_error(fmt::format("{}:{}: {}", src, line_no, why)); };
  while (std::getline(in, raw)) {
    ++line_no;
    if (std::string why = clean_line(raw, line_no); !why.empty()) return fail(why);
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const auto f = split_csv(line);
    if (columns.empty()) {
      if (std::string why = read_header(f, columns); !why.empty()) return fail(why);
      continue;
    }
    if (f.size() != columns.size()) return fail(fmt::format("expected {} fields as in the header, got {}", columns.size(), f.size()));
    RegisterEntry e;
    e.line = line_no;
    if (std::string why = read_entry(Row{columns, f}, e); !why.empty()) return fail(why);
    if (std::string why = map.add(std::move(e)); !why.empty()) return fail(why);
  }
  if (columns.empty()) return core::parse_error(src + ": empty register map, expected a header row (name,table,address,type,...)");
  if (map.entries_.empty()) return core::parse_error(src + ": the register map maps no points");
  return map;
}

std::string RegisterMap::add(RegisterEntry e) {
  auto& index = index_[static_cast<int>(e.table)];
  if (static_cast<int>(index.size()) < e.address + e.width()) index.resize(static_cast<std::size_t>(e.address + e.width()), -1);
  for (int a = e.address; a < e.address + e.width(); ++a) {
    if (const auto other = index[static_cast<std::size_t>(a)]; other >= 0) {
      const RegisterEntry& o = entries_[static_cast<std::size_t>(other)];
      return fmt::format("{} address {} overlaps '{}' of line {}", to_string(e.table), a, o.point->name, o.line);
    }
    index[static_cast<std::size_t>(a)] = static_cast<std::int32_t>(entries_.size());
  }
  entries_.push_back(std::move(e));
  return "";
}

RegisterMap::Hit RegisterMap::find(Table table, int address) const noexcept {
  const auto& index = index_[static_cast<int>(table)];
  if (address < 0 || address >= static_cast<int>(index.size())) return {};
  const auto i = index[static_cast<std::size_t>(address)];
  if (i < 0) return {};
  const RegisterEntry& e = entries_[static_cast<std::size_t>(i)];
  return {&e, address - e.address};
}

void encode_value(const RegisterEntry& e, double v, std::uint16_t* w) noexcept {
  auto scaled = [&](double lo, double hi, double sentinel) {
    if (std::isnan(v)) return sentinel;
    return std::clamp(std::round(v * e.scale), lo, hi);
  };
  switch (e.type) {
    case DataType::kBool: w[0] = v != 0.0 && !std::isnan(v) ? 1 : 0; break;
    case DataType::kUint16: w[0] = static_cast<std::uint16_t>(scaled(0, 65534, 65535)); break;
    case DataType::kInt16: w[0] = static_cast<std::uint16_t>(static_cast<std::int16_t>(scaled(-32767, 32767, -32768))); break;
    case DataType::kUint32: {
      const auto r = core::encode_u32(static_cast<std::uint32_t>(scaled(0, 4294967294.0, 4294967295.0)), e.word_order);
      w[0] = r[0], w[1] = r[1];
      break;
    }
    case DataType::kInt32: {
      const auto r = core::encode_i32(static_cast<std::int32_t>(scaled(-2147483647.0, 2147483647.0, -2147483648.0)), e.word_order);
      w[0] = r[0], w[1] = r[1];
      break;
    }
    case DataType::kFloat32: {
      const auto r = core::encode_f32(static_cast<float>(v), e.word_order);
      w[0] = r[0], w[1] = r[1];
      break;
    }
    case DataType::kKey64: w[0] = w[1] = w[2] = w[3] = 0; break;  // a key reads back as zeros
  }
}

double decode_value(const RegisterEntry& e, const std::uint16_t* w) noexcept {
  switch (e.type) {
    case DataType::kBool: return w[0] ? 1.0 : 0.0;
    case DataType::kUint16: return w[0] / e.scale;
    case DataType::kInt16: return static_cast<std::int16_t>(w[0]) / e.scale;
    case DataType::kUint32: return core::decode_u32({w[0], w[1]}, e.word_order) / e.scale;
    case DataType::kInt32: return core::decode_i32({w[0], w[1]}, e.word_order) / e.scale;
    case DataType::kFloat32: return core::decode_f32({w[0], w[1]}, e.word_order);
    case DataType::kKey64: return 0.0;  // see key_value()
  }
  return 0.0;
}

std::uint64_t key_value(const std::uint16_t* w) noexcept {
  return (std::uint64_t{w[0]} << 48) | (std::uint64_t{w[1]} << 32) | (std::uint64_t{w[2]} << 16) | w[3];
}

core::Status narrow_limits(const RegisterMap& map, points::WriteLimits& limits) {
  for (const RegisterEntry& e : map.entries()) {
    if (!e.writable) continue;
    const std::string at = map.source() + ":" + std::to_string(e.line);
    if (auto s = limits.narrow(e.point->id, e.min, e.max, at); !s) return s;
  }
  for (const RegisterEntry& e : map.entries()) {
    if (!e.writable || !e.default_value) continue;
    if (auto why = limits.check(e.point->id, *e.default_value); !why.empty())
      return core::invalid_argument(map.source() + ":" + std::to_string(e.line) + ": default: " + why);
  }
  return core::ok();
}

}  // namespace epa::modbus
