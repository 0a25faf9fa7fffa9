#include "modbus/register_export.hpp"

#include <cstdio>
#include <sstream>

#include "core/format.hpp"
#include "modbus/device_identification.hpp"
#include "modbus/register_guide.hpp"

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

std::string markdown_cell(std::string_view text) {
  std::string cell;
  for (const char c : text) {
    if (c == '|') cell += '\\';
    cell += c;
  }
  return cell;
}

namespace {

// What an integrator needs besides the table: function codes, what reads and writes may cover,
// unit ids and device identification (the same objects the request handler sends).
void write_protocol_notes(std::ostream& out, const RegisterMap& map) {
  out << "Function codes 1, 2, 3, 4, 5, 6, 15, 16, 23 and 43/14 (read device identification). Input and holding "
         "registers answer only where a point is mapped: a read across a gap is exception 02. Coils and discrete inputs "
         "read in blocks of 16: every address from 0 up to the table's end rounded up to a multiple of 16 is readable, "
         "and one that no point is mapped to reads 0 (reserved); writing it is exception 02.";
  std::string bits;
  for (const Table t : {Table::kCoil, Table::kDiscreteInput}) {
    if (map.readable_end(t) == 0) continue;
    bits += std::string(bits.empty() ? "" : ", ") + (t == Table::kCoil ? "coils 0-" : "discrete inputs 0-") +
            std::to_string(map.readable_end(t) - 1);
  }
  out << " Readable bits of this map: " << (bits.empty() ? "none" : bits) << ".\n\n";
  out << "Unit id: `[modbus] unit_id` (1 by default), and 0 and 0xFF, which TCP clients send for \"the server itself\" "
         "(`[modbus] alias_unit_ids = [0, 255]`, the default; `[]` for unit_id only); another unit id gets exception 0B.\n\n";
  const DeviceIdentity identity = appliance_identity(map.source(), status_page_url("<[web] port>"));
  out << "Device identification (FC43, MEI type 0x0E), conformity level 0x82 (basic and regular objects, stream and "
         "individual access). Read code 01 gives objects 0x00-0x02, 02 and 03 give 0x00-0x06 (there are no extended "
         "objects), 04 the object asked for (another id: exception 02); another read code is exception 03, another MEI "
         "type exception 01. An answer that would pass 253 bytes says \"more follows\" and the next object id.\n\n"
      << "| object | name | value |\n| --- | --- | --- |\n";
  static constexpr const char* kNames[] = {"VendorName", "ProductCode", "MajorMinorRevision", "VendorUrl", "ProductName",
                                           "ModelName", "UserApplicationName"};
  for (std::size_t i = 0; i < identity.objects.size(); ++i) {
    char id[8];
    std::snprintf(id, sizeof id, "0x%02zX", i);
    out << "| " << id << " | " << kNames[i] << " | ";
    if (i == 2) out << "the firmware version, as `epa --version` prints it and version_major/minor/patch read";
    else out << "`" << identity.objects[i] << "`";
    if (i == 3) out << " (the appliance's status page, at the address the client reached it by; empty with `[web] enabled = false`)";
    if (i == 6) out << " (the register map's file name)";
    out << " |\n";
  }
  out << "\n";
}

}  // namespace

std::string export_markdown(const RegisterMap& map) {
  std::ostringstream out;
  out << "# Modbus register map\n\nSource: `" << map.source() << "`. Addresses are 0-based protocol addresses; the "
      << "reference is the 1-based alias many HMIs use. 32-bit values take two registers, word order as given "
         "(ABCD: high word first). Integer registers hold round(value x scale); NaN (\"never reached\") reads as the "
         "type's sentinel (int16 -32768, uint16 65535, int32 -2147483648, uint32 4294967295).\n\n";
  write_positioning_guide(out, map);
  out << "## Protocol\n\n";
  write_protocol_notes(out, map);
  out << "## Every register\n\n";
  out << "| point | table | address | reference | type | word order | scale | unit | access | range | default | persisted | description |\n"
      << "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  for (const auto& e : map.entries()) {
    const std::string last = e.width() == 2 ? "-" + std::to_string(e.address + 1) : "";
    out << "| " << e.point->name << " | " << to_string(e.table) << " | " << e.address << last << " | "
        << reference_alias(e.table, e.address) << " | " << to_string(e.type) << " | " << word_order_text(e) << " | "
        << (e.type == DataType::kFloat32 || e.type == DataType::kBool ? "" : core::format_number(e.scale)) << " | " << e.unit
        << " | " << (e.writable ? "rw" : "r") << (e.writable && e.point->tuning() ? " (unlock)" : "") << " | " << range_text(e)
        << " | " << (e.default_value ? core::format_number(*e.default_value) : "") << " | " << (e.persisted ? "yes" : "")
        << " | " << markdown_cell(e.description) << " |\n";
  }
  return out.str();
}

std::string export_csv(const RegisterMap& map) {
  std::ostringstream out;
  // unlock: yes where a write needs the unlock first (the Markdown's "rw (unlock)")
  out << "point,table,address,reference,type,word_order,scale,unit,access,unlock,min,max,default,persisted,description\n";
  for (const auto& e : map.entries()) {
    out << e.point->name << ',' << to_string(e.table) << ',' << e.address << ',' << reference_alias(e.table, e.address) << ','
        << to_string(e.type) << ',' << word_order_text(e) << ',' << core::format_number(e.scale) << ',' << csv_field(e.unit) << ','
        << (e.writable ? "rw" : "r") << ',' << (e.writable && e.point->tuning() ? "yes" : "no") << ','
        << (e.writable ? core::format_number(e.min) : "") << ','
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
        << (p.writable() ? core::format_number(p.min) + " .. " + core::format_number(p.max) : "") << " | " << markdown_cell(p.description)
        << " |\n";
  }
  return out.str();
}

}  // namespace epa::modbus
