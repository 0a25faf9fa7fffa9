#include "modbus/register_guide.hpp"

#include <string>

#include "modbus/register_export.hpp"
#include "points/point_id.hpp"
#include "points/position_records.hpp"
#include "runtime/axis_words.hpp"

namespace epa::modbus {

namespace {

using P = points::PointId;

const RegisterEntry* entry_of(const RegisterMap& map, P id) {
  for (const auto& e : map.entries())
    if (e.point->id == id) return &e;
  return nullptr;
}

const char* table_name(Table t) {
  switch (t) {
    case Table::kCoil: return "coil";
    case Table::kDiscreteInput: return "discrete input";
    case Table::kInputRegister: return "input register";
    case Table::kHoldingRegister: return "holding register";
  }
  return "";
}

// "holding register 50 / 40051", or a plain statement that this map leaves the point out.
std::string where(const RegisterMap& map, P id) {
  const RegisterEntry* e = entry_of(map, id);
  if (e == nullptr) return "nowhere: `" + std::string(points::name(id)) + "` is not in this map";
  return std::string(table_name(e->table)) + " " + std::to_string(e->address) + " / " + reference_alias(e->table, e->address);
}

std::string address(const RegisterMap& map, P id) {
  const RegisterEntry* e = entry_of(map, id);
  return e == nullptr ? "?" : std::to_string(e->address);
}

void write_bit_table(std::ostream& out, const RegisterMap& map, P first_bit, int bits, const char* single_table) {
  out << "| bit | mask | name | as a single " << single_table << " | meaning |\n| --- | --- | --- | --- | --- |\n";
  for (int i = 0; i < bits; ++i) {
    const P id = points::indexed_id(first_bit, static_cast<std::size_t>(i));
    const RegisterEntry* e = entry_of(map, id);
    const auto& def = points::point(id);
    out << "| " << i << " | 0x" << std::hex << (1u << i) << std::dec << " | " << def.name << " | "
        << (e ? std::to_string(e->address) + " (" + reference_alias(e->table, e->address) + ")" : "not mapped") << " | "
        << markdown_cell(def.description) << " |\n";
  }
  out << "\n";
}

void write_words(std::ostream& out, const RegisterMap& map) {
  out << "## The control word and the status word, bit by bit\n\n";
  if (entry_of(map, P::kControlWord) == nullptr && entry_of(map, P::kStatusWord) == nullptr &&
      entry_of(map, P::kControlBit0) == nullptr && entry_of(map, P::kStatusBit0) == nullptr) {
    out << "This map has neither word nor their bits.\n\n";
    return;
  }
  out
      << "The control word is " << where(map, P::kControlWord) << "; write it whole, or its bits one at a time as coils. "
      << "Edges (start, halt, reset) act when the bit goes from 0 to 1, so write 0 again before the next edge. The status word "
      << "is " << where(map, P::kStatusWord) << "; its bits also read one at a time as discrete inputs.\n\n"
      << "Control word:\n\n";
  write_bit_table(out, map, P::kControlBit0, runtime::kControlBits, "coil");
  out << "Status word:\n\n";
  write_bit_table(out, map, P::kStatusBit0, runtime::kStatusBits, "discrete input");
}

void write_records(std::ostream& out, const RegisterMap& map) {
  const RegisterEntry* first = entry_of(map, P::kRecordTarget0);
  out << "## Position records\n\n";
  if (first == nullptr) {
    out << "This map has no position records (`record1_target_mm` and the rest are not mapped).\n\n";
    return;
  }
  const RegisterEntry* second = entry_of(map, points::indexed_id(P::kRecordTarget0, 1));
  const int stride = second ? second->address - first->address : 0;
  out << points::kPositionRecords << " records; record N (1.." << points::kPositionRecords << ") starts at holding register "
      << first->address;
  if (stride > 0) out << " + " << stride << "·(N-1)";
  out << ". Each holds, in order:\n\n| field | point | type | meaning |\n| --- | --- | --- | --- |\n";
  const P fields[] = {P::kRecordTarget0, P::kRecordSpeed0, P::kRecordWindow0, P::kRecordController0, P::kRecordApproach0};
  for (const P f : fields) {
    const RegisterEntry* e = entry_of(map, f);
    out << "| +" << (e ? std::to_string(e->address - first->address) : std::string("?")) << " | " << points::name(f) << " | "
        << (e ? std::string(to_string(e->type)) + (e->width() == 2 ? " " + std::string(core::to_string(e->word_order)) : "") : "not mapped")
        << " | " << markdown_cell(points::point(f).description) << " |\n";
  }
  out << "\nRecords are tuning: write them after the unlock, " << where(map, P::kUnlock)
      << ", on the same connection (the unlock ends with it: a tool that connects once per call, like mbpoll, cannot "
         "edit records; it can still start them), or over HTTP with the token (`epa records`, `POST /api/points`). They are kept in the store and survive a restart. "
         "Select one with record_select, " << where(map, P::kRecordSelect) << ", then give a start edge.\n\n";
}

// The walk-through's points; a map without one of them gets the list instead of wrong steps.
constexpr P kWalkThroughPoints[] = {P::kPosition, P::kSetpoint, P::kMode, P::kStatusWord, P::kControlWord};

void write_first_ten_minutes(std::ostream& out, const RegisterMap& map) {
  std::string missing;
  for (const P id : kWalkThroughPoints)
    if (entry_of(map, id) == nullptr) missing += std::string(missing.empty() ? "" : ", ") + "`" + std::string(points::name(id)) + "`";
  if (!missing.empty()) {
    out << "## First 10 minutes with your HMI\n\nThis map leaves out " << missing
        << ", which the walk-through uses: see `registers/epa.csv`'s documentation for it, and the table below for what "
           "this map serves.\n\n";
    return;
  }
  const std::string position = address(map, P::kPosition), status = address(map, P::kStatusWord),
                    control = address(map, P::kControlWord), setpoint = address(map, P::kSetpoint), mode = address(map, P::kMode);
  out << "## First 10 minutes with your HMI\n\n"
      << "1. **Connect.** Modbus TCP, port `[modbus] port` (502 in `config/epa.toml`), unit id `[modbus] unit_id` (1; 0 and "
         "255 are answered too). FC43/14 tells you what you reached: vendor, product and the firmware version.\n"
      << "2. **Word order.** Every 32-bit value of this map is ABCD unless its row says otherwise: the high word in the lower "
         "register, each word big-endian (IEEE 754 float, \"big-endian\", \"no word swap\"). Set your client so, per client:\n\n"
      << "   | client | reading position_mm, " << where(map, P::kPosition) << " | writing setpoint_mm, "
      << where(map, P::kSetpoint) << " |\n   | --- | --- | --- |\n"
      << "   | mbpoll | `mbpoll -m tcp -a 1 -0 -1 -B -t 3:float -r " << position << " HOST`: `-B` is big-endian word order (without "
         "it mbpoll assumes CDAB), `-0` makes `-r` the 0-based address, `-1` polls once | `mbpoll -m tcp -a 1 -0 -1 -B -t 4:float -r "
      << setpoint << " HOST 150` (values after the host) |\n"
      << "   | pymodbus 3.0 | `r = client.read_input_registers(" << position << ", 2, slave=1)` then "
         "`struct.unpack('>f', struct.pack('>HH', *r.registers))[0]`; with `BinaryPayloadDecoder` pass both "
         "`byteorder=Endian.Big` and `wordorder=Endian.Big` (its defaults are little-endian: with the word order alone "
         "150.0 decodes as 1.6e-25) | `client.write_registers(" << setpoint
      << ", list(struct.unpack('>HH', struct.pack('>f', 150.0))), slave=1)` |\n"
      << "   | Node modbus-serial | `(await client.readInputRegisters(" << position << ", 2)).buffer.readFloatBE(0)` | "
         "`b.writeFloatBE(150)` into a 4-byte Buffer, then `client.writeRegisters(" << setpoint
      << ", [b.readUInt16BE(0), b.readUInt16BE(2)])` |\n"
      << "   | an HMI / SCADA driver | data type REAL or FLOAT32, byte order ABCD / big-endian / 1234, word swap off | the "
         "same; if it only knows CDAB, give it a site map with `word_order` CDAB (`registers/examples/legacy-hmi.csv`) |\n\n"
      << "   Check it on a value you know: 150.0 is the words `0x4316 0x0000`. A float written with its words swapped "
         "(100.0 becomes 2.4e-41) is refused with exception 03, not taken as a tiny setpoint.\n"
      << "3. **Look.** Read the status word (input register " << status << "): bit 0 ready means the axis can be enabled; "
         "bit 7 means a fault is latched, and fault_code, " << where(map, P::kFaultCode) << ", says which.\n"
      << "4. **Enable.** Write 1 (RUN) to mode, holding register " << mode << ". The axis holds where the piston is "
         "(`[motion] enable_holds_position`); the setpoint follows the piston, so nothing moves yet.\n"
      << "5. **Move, with the handshake.** Write the target to setpoint_mm (holding " << setpoint << ", float) or choose a "
         "record with record_select, then set control-word bit 0 (start): write 1 to holding " << control << ". Poll the "
         "status word until bit 8 (ack) is 1: the loop has taken the start. Write 0 to the control word; ack drops to 0. "
         "The move is done when bit 4 (target_reached) and bit 3 (in_position) are both 1; bit 2 (moving) is 1 meanwhile, "
         "from the write on: a read answered after a target was accepted never shows the old target's in_position. "
         "Then move_number, move_end and the move_* metrics (input registers 70-83, 141) describe it, as its run file does. "
         "If the law leaves the piston standing outside the window (a dead band, stiction), moving clears after "
         "`[motion] standstill_time_s` and bit 12 (off_target) and bit 6 (warning) say so: wait for moving to clear, then "
         "look at in_position, and bound the wait. Writing a new setpoint in RUN also moves the axis, without the "
         "handshake; so does a setpoint written in the same request as the enable (mode, then setpoint), even the one "
         "it had. Writing the setpoint it already has again in RUN does nothing.\n"
      << "6. **Halt.** Set bit 1 (value 2): the axis brakes and holds where it stops (bit 9 halted); bit 2 (moving) clears "
         "when it stands, and bit 3 (in_position) stays 0 unless it stopped within the window of the move's target. Clear it again.\n"
      << "7. **Jog.** Mode 2 (MANUAL), then hold bit 2 (jog_plus, value 4) or bit 3 (jog_minus, value 8) set and write the "
         "control word (or the heartbeat) again at least every second: without that keep-alive the jog brakes. Clear the "
         "bit to stop.\n"
      << "8. **Faults.** A fault stops the axis and latches; bit 4 of the control word (value 16, an edge) or a 1 written to "
         "reset clears it, back to STOP; after a soft-limit fault, MANUAL or RUN may bring the piston back inside (driving it "
         "further out faults again). The history keeps the newest faults with their time, mode, position, setpoint "
         "and valve command, newest first: fault_history_count, " << where(map, P::kFaultHistoryCount)
      << ", counts them since the store was created, the entries follow it. `GET /api/faults` on the web port and `epa "
         "faults` show the same.\n"
      << "9. **Supervise.** If `[limits] heartbeat_timeout_s` is set, increment heartbeat, " << where(map, P::kHeartbeat)
      << ", faster than that: when it stops, the appliance faults (heartbeat lost) and the valve goes safe.\n\n";
}

}  // namespace

void write_positioning_guide(std::ostream& out, const RegisterMap& map) {
  write_first_ten_minutes(out, map);
  write_words(out, map);
  write_records(out, map);
}

}  // namespace epa::modbus
