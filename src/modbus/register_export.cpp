#include "modbus/register_export.hpp"

#include <cstdio>
#include <sstream>

#include "core/format.hpp"

namespace epa::modbus {

namespace {

std::string range_text(const RegisterEntry& e) {
  if (!e.writable) return "";
  return core::format_number(e.min) + " .. " + core::format_number(e.max);
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string word_order_text(const RegisterEntry& e) { return e.width() == 2 ? std::string(core::to_string(e.word_order)) : ""; }

}  // namespace

std::string reference_alias(Table table, int address) {
  const char prefix = table == Table::kCoil ? '0' : table == Table::kDiscreteInput ? '1' : table == Table::kInputRegister ? '3' : '4';
  char buf[16];
  std::snprintf(buf, sizeof buf, address < 9999 ? "%c%04d" : "%c%05d", prefix, address + 1);
  return buf;
}

std::string export_markdown(const RegisterMap& map) {
  std::ostringstream out;
  out << "# Modbus register map\n\nSource: `" << map.source() << "`. Addresses are 0-based protocol addresses; the "
      << "reference is the 1-based alias many HMIs use. 32-bit values take two registers, word order as given "
         "(ABCD: high word first). Integer registers hold round(value x scale); NaN (\"never reached\") reads as the "
         "type's sentinel (int16 -32768, uint16 65535, int32 -2147483648, uint32 4294967295).\n\n"
      << "| point | table | address | reference | type | word order | scale | unit | access | range | default | persisted | description |\n"
      << "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const auto& e : map.entries()) {
    const std::string last = e.width() == 2 ? "-" + std::to_string(e.address + 1) : "";
    out << "| " << e.point->name << " | " << to_string(e.table) << " | " << e.address << last << " | "
        << reference_alias(e.table, e.address) << " | " << to_string(e.type) << " | " << word_order_text(e) << " | "
        << (e.type == DataType::kFloat32 || e.type == DataType::kBool ? "" : core::format_number(e.scale)) << " | " << e.unit
        << " | " << (e.writable ? "rw" : "r") << (e.writable && e.point->tuning() ? " (unlock)" : "") << " | " << range_text(e)
        << " | " << (e.default_value ? core::format_number(*e.default_value) : "") << " | " << (e.persisted ? "yes" : "")
        << " | " << e.description << " |\n";
  }
  return out.str();
}

std::string export_csv(const RegisterMap& map) {
  std::ostringstream out;
  out << "point,table,address,reference,type,word_order,scale,unit,access,min,max,default,persisted,description\n";
  for (const auto& e : map.entries()) {
    out << e.point->name << ',' << to_string(e.table) << ',' << e.address << ',' << reference_alias(e.table, e.address) << ','
        << to_string(e.type) << ',' << word_order_text(e) << ',' << core::format_number(e.scale) << ',' << csv_field(e.unit) << ','
        << (e.writable ? "rw" : "r") << ',' << (e.writable ? core::format_number(e.min) : "") << ','
        << (e.writable ? core::format_number(e.max) : "") << ','
        << (e.default_value ? core::format_number(*e.default_value) : "") << ',' << (e.persisted ? "yes" : "no") << ','
        << csv_field(e.description) << '\n';
  }
  return out.str();
}

std::string points_markdown() {
  std::ostringstream out;
  out << "| point | unit | writes | range | description |\n| --- | --- | --- | --- | --- |\n";
  for (const auto& p : points::point_catalog()) {
    out << "| " << p.name << " | " << p.unit << " | " << (p.tuning() ? "yes, after unlock" : p.writable() ? "yes" : "") << " | "
        << (p.writable() ? core::format_number(p.min) + " .. " + core::format_number(p.max) : "") << " | " << p.description << " |\n";
  }
  return out.str();
}

}  // namespace epa::modbus
