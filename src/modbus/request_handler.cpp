#include "modbus/request_handler.hpp"

#include <modbus.h>

#include <algorithm>
#include <cmath>

#include "core/tiny_number.hpp"
#include "modbus/exception_codes.hpp"
#include "modbus/refusal_exception.hpp"

namespace epa::modbus {

static_assert(kIllegalFunction == MODBUS_EXCEPTION_ILLEGAL_FUNCTION && kIllegalAddress == MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS &&
              kIllegalValue == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE && kCannotApply == MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE &&
              kOtherUnit == MODBUS_EXCEPTION_GATEWAY_TARGET, "the exception codes are libmodbus's");

namespace {

constexpr int kHeader = 7;  // MBAP: transaction, protocol, length, unit
constexpr int kDeviceIdentification = 0x2B;  // FC43, encapsulated interface transport: libmodbus does not answer it

int be16(const std::uint8_t* p) { return (p[0] << 8) | p[1]; }


std::uint16_t* table_words(_modbus_mapping_t* m, Table t) {
  return t == Table::kHoldingRegister ? m->tab_registers : m->tab_input_registers;
}
std::uint8_t* table_bits(_modbus_mapping_t* m, Table t) { return t == Table::kCoil ? m->tab_bits : m->tab_input_bits; }

}  // namespace

RequestHandler::RequestHandler(const RegisterMap& map, WritePolicy policy, std::vector<int> unit_ids, std::string_view status_page_url,
                               points::WriteGate& gate, runtime::LoopChannels& channels, Log log)
    : map_(map), policy_(std::move(policy)), unit_ids_(std::move(unit_ids)), identity_(appliance_identity(map.source(), status_page_url)), gate_(gate),
      channels_(channels), log_(std::move(log)), unlock_(policy_.unlock_key) {}

namespace {
// Whether tuning points refuse this client's writes (the locked point): its role's, or its unlock's.
bool locked(const Session& session, std::int64_t now_ns) {
  return session.rights ? *session.rights != points::Rights::kTune : now_ns >= session.unlocked_until_ns;
}
}  // namespace

points::InterfaceStatus RequestHandler::status(const Session& session, std::int64_t now_ns) const {
  const core::ChangeCounters changes = gate_.counters();
  points::InterfaceStatus s{static_cast<std::uint32_t>(changes.accepted), static_cast<std::uint32_t>(changes.saved), changes.saving,
                            requests_, clients_, locked(session, now_ns), unlock_.failures(), gate_.commission_view(), gate_.health_view()};
  s.disk_low = changes.disk_low;
  s.records = gate_.records();
  s.record_select = gate_.record_select();
  s.fault_history_count = channels_.fault_history.copy_newest(s.recent_faults);
  s.limits = gate_.configured_limits();
  return s;
}

Reply RequestHandler::handle(const std::uint8_t* req, int length, Session& session, std::int64_t now_ns,
                            _modbus_mapping_t* image) {
  Reply reply;
  reply.exception = respond(req, length, session, now_ns, image, reply.pdu);
  if (reply.exception) reply.pdu.clear();
  return reply;
}

std::uint8_t RequestHandler::respond(const std::uint8_t* req, int length, Session& session, std::int64_t now_ns,
                                     _modbus_mapping_t* image, std::vector<std::uint8_t>& pdu) {
  ++requests_;
  if (length < kHeader + 1) return kIllegalFunction;
  const int unit = req[6];
  if (std::find(unit_ids_.begin(), unit_ids_.end(), unit) == unit_ids_.end()) return kOtherUnit;
  const int fc = req[kHeader];
  const std::uint8_t* d = req + kHeader + 1;
  const int data_length = length - kHeader - 1;
  if (fc == kDeviceIdentification) {
    if (session.local_address.empty()) return read_device_identification(d, data_length, identity_, pdu);
    return read_device_identification(d, data_length, with_host(identity_, session.local_address), pdu);
  }
  const runtime::Snapshot snap = gate_.snapshot();  // with this client's (and others') accepted writes
  std::vector<Write> writes;

  switch (fc) {
    case MODBUS_FC_READ_COILS:
    case MODBUS_FC_READ_DISCRETE_INPUTS:
    case MODBUS_FC_READ_HOLDING_REGISTERS:
    case MODBUS_FC_READ_INPUT_REGISTERS: {
      if (data_length < 4) return kIllegalValue;
      const Table t = fc == 1 ? Table::kCoil : fc == 2 ? Table::kDiscreteInput : fc == 3 ? Table::kHoldingRegister : Table::kInputRegister;
      return read_into(t, be16(d), be16(d + 2), snap, session, now_ns, image);
    }
    case MODBUS_FC_WRITE_SINGLE_COIL: {
      if (data_length < 4) return kIllegalValue;
      const int v = be16(d + 2);
      if (v != 0xFF00 && v != 0x0000) return kIllegalValue;
      const std::uint8_t bit[1] = {static_cast<std::uint8_t>(v == 0xFF00 ? 1 : 0)};
      if (auto e = collect_coil_writes(be16(d), 1, bit, writes)) return e;
      return apply_writes(writes, session, now_ns);
    }
    case MODBUS_FC_WRITE_SINGLE_REGISTER: {
      if (data_length < 4) return kIllegalValue;
      if (auto e = collect_register_writes(be16(d), 1, d + 2, writes)) return e;
      return apply_writes(writes, session, now_ns);
    }
    case MODBUS_FC_WRITE_MULTIPLE_COILS: {
      if (data_length < 5) return kIllegalValue;
      const int quantity = be16(d + 2);
      if (quantity < 1 || quantity > MODBUS_MAX_WRITE_BITS || d[4] != (quantity + 7) / 8 || data_length < 5 + d[4]) return kIllegalValue;
      std::vector<std::uint8_t> bits(static_cast<std::size_t>(quantity));
      for (int i = 0; i < quantity; ++i) bits[static_cast<std::size_t>(i)] = (d[5 + i / 8] >> (i % 8)) & 1;
      if (auto e = collect_coil_writes(be16(d), quantity, bits.data(), writes)) return e;
      return apply_writes(writes, session, now_ns);
    }
    case MODBUS_FC_WRITE_MULTIPLE_REGISTERS: {
      if (data_length < 5) return kIllegalValue;
      const int quantity = be16(d + 2);
      if (quantity < 1 || quantity > MODBUS_MAX_WRITE_REGISTERS || d[4] != quantity * 2 || data_length < 5 + d[4]) return kIllegalValue;
      if (auto e = collect_register_writes(be16(d), quantity, d + 5, writes)) return e;
      return apply_writes(writes, session, now_ns);
    }
    case MODBUS_FC_WRITE_AND_READ_REGISTERS: {
      if (data_length < 9) return kIllegalValue;
      const int read_quantity = be16(d + 2), write_quantity = be16(d + 6);
      if (read_quantity < 1 || read_quantity > MODBUS_MAX_WR_READ_REGISTERS || write_quantity < 1 ||
          write_quantity > MODBUS_MAX_WR_WRITE_REGISTERS || d[8] != write_quantity * 2 || data_length < 9 + d[8])
        return kIllegalValue;
      if (auto e = collect_register_writes(be16(d + 4), write_quantity, d + 9, writes)) return e;
      // The read part must be valid too before anything is applied.
      for (int a = be16(d); a < be16(d) + read_quantity; ++a)
        if (!map_.find(Table::kHoldingRegister, a).entry) return kIllegalAddress;
      if (auto e = apply_writes(writes, session, now_ns)) return e;
      // modbus_reply writes first, then reads: the answer shows the written values.
      return read_into(Table::kHoldingRegister, be16(d), read_quantity, gate_.snapshot(), session, now_ns, image);
    }
    default: return kIllegalFunction;
  }
}

std::uint8_t RequestHandler::read_into(Table t, int address, int quantity, const runtime::Snapshot& snap,
                                       const Session& session, std::int64_t now_ns, _modbus_mapping_t* image) {
  const int max = is_bit_table(t) ? MODBUS_MAX_READ_BITS : MODBUS_MAX_READ_REGISTERS;
  if (quantity < 1 || quantity > max) return kIllegalValue;
  if (address + quantity > 65536) return kIllegalAddress;
  // Bit tables up to their end rounded up to 16, where a bit nothing is mapped to reads 0
  // (reserved); register tables only where points are mapped.
  if (is_bit_table(t) && address + quantity > map_.readable_end(t)) return kIllegalAddress;
  const points::InterfaceStatus server = status(session, now_ns);
  const points::PointContext ctx{snap, server};
  for (int a = address; a < address + quantity;) {
    const auto hit = map_.find(t, a);
    if (!hit.entry) {
      if (!is_bit_table(t)) return kIllegalAddress;
      table_bits(image, t)[a++] = 0;
      continue;
    }
    const RegisterEntry& e = *hit.entry;
    const double value = e.point->value(ctx);
    if (is_bit_table(t)) {
      table_bits(image, t)[e.address] = value != 0.0 ? 1 : 0;
    } else {
      encode_value(e, value, table_words(image, t) + e.address);  // the whole value, even if half is asked
    }
    a = e.address + e.width();
  }
  return 0;
}

std::uint8_t RequestHandler::collect_register_writes(int address, int quantity, const std::uint8_t* bytes,
                                                     std::vector<Write>& out) const {
  if (address + quantity > 65536) return kIllegalAddress;
  for (int a = address; a < address + quantity;) {
    const auto hit = map_.find(Table::kHoldingRegister, a);
    if (!hit.entry || !hit.entry->writable) return kIllegalAddress;
    const RegisterEntry& e = *hit.entry;
    if (hit.offset != 0 || e.address + e.width() > address + quantity) return kIllegalValue;  // half a 32-bit value
    std::uint16_t words[4] = {};
    for (int i = 0; i < e.width(); ++i) words[i] = static_cast<std::uint16_t>(be16(bytes + 2 * (a - address + i)));
    const double value = decode_value(e, words);
    // A subnormal float is what a client with the wrong word order writes (100.0 as CDAB reads
    // 2.4e-41): within most ranges, and a setpoint of 0 mm. Nobody means one: refused, 03 (HTTP alike).
    if (e.type == DataType::kFloat32 && core::is_tiny_number(value)) return kIllegalValue;
    out.push_back({&e, value, e.type == DataType::kKey64 ? key_value(words) : 0});
    a += e.width();
  }
  return 0;
}

std::uint8_t RequestHandler::collect_coil_writes(int address, int quantity, const std::uint8_t* bits, std::vector<Write>& out) const {
  if (address + quantity > 65536) return kIllegalAddress;
  for (int i = 0; i < quantity; ++i) {
    const auto hit = map_.find(Table::kCoil, address + i);
    if (!hit.entry || !hit.entry->writable) return kIllegalAddress;
    out.push_back({hit.entry, bits[i] ? 1.0 : 0.0});
  }
  return 0;
}

std::uint8_t RequestHandler::take_key(const Write& key, const Session& session, std::int64_t now_ns) {
  const UnlockGuard::Attempt a = unlock_.attempt({session.address, session.peer, session.opened_ns}, key.key, now_ns);
  if (a.verdict == UnlockGuard::Verdict::kUnlocked) return 0;
  if (a.verdict == UnlockGuard::Verdict::kNoKey) return kIllegalValue;  // none configured: nothing to guess
  // A wrong key is logged and audited each time (at most kFreeAttempts before a back-off), the
  // start of a back-off too; attempts during one are refused unseen and only counted.
  if (a.verdict == UnlockGuard::Verdict::kLockedOut) return kCannotApply;
  std::string what = "wrong unlock key";
  if (a.lockout_started && !a.address_lockout)
    what += "; unlock writes on this connection refused for " + std::to_string(a.backoff_ns / 1'000'000'000) + " s";
  if (a.address_lockout)
    what += "; unlock writes from " + session.address + " refused for " + std::to_string(a.backoff_ns / 1'000'000'000) +
            " s, except from a connection open 2 s that sent no wrong key";
  if (log_) log_("modbus: " + session.peer + ": " + what + " (" + std::to_string(unlock_.failures()) + " refused attempts since start)");
  // The audit trail says who and what, each in its column: an event on `unlock`, nothing changed
  // (the why is in the log line above).
  gate_.record_event({{core::unix_time_ms(), "modbus " + session.peer, std::string(key.entry->point->name), NAN, NAN}});
  return kIllegalValue;
}

std::uint8_t RequestHandler::apply_writes(const std::vector<Write>& writes, Session& session, std::int64_t now_ns) {
  // The unlock key is this interface's own; everything else goes through the gate as one group.
  const points::Requester who = requester(session, now_ns);
  std::vector<points::PointWrite> group;
  bool unlock = false;
  for (const auto& w : writes) {
    if (w.entry->point->gated()) {
      group.push_back({w.entry->point->id, w.value});
      continue;
    }
    if (!who.may_write || session.rights) return kCannotApply;  // on the secure port the role decides, not the key
    if (auto e = take_key(w, session, now_ns)) return e;
    unlock = true;
  }
  if (!group.empty())
    if (const auto r = gate_.submit(group, who); !r.accepted()) return exception_code(r.refusal);
  if (unlock) {
    // An unlock opens the tuning to this connection: in the audit trail as unlock 0 -> 1 (once per
    // unlock; a key written again while open renews it and is not a change).
    if (now_ns >= session.unlocked_until_ns) {
      if (log_) log_("modbus: " + session.peer + ": tuning unlocked for this connection");
      gate_.record_event({{core::unix_time_ms(), "modbus " + session.peer, std::string(points::name(points::PointId::kUnlock)), 0.0, 1.0}});
    }
    session.unlocked_until_ns = now_ns + static_cast<std::int64_t>(policy_.unlock_timeout_s * 1e9);
  }
  return 0;
}

// Who writes: on the secure port, by the role in the client's certificate; on plain Modbus, by
// write_clients and this connection's unlock. A read-only server refuses every write on both.
points::Requester RequestHandler::requester(const Session& session, std::int64_t now_ns) const {
  points::Requester who;
  if (session.rights) {
    who = points::requester_with_rights("modbus-tls " + session.peer + " " + session.subject + " (" + session.role + ")", session.subject,
                                        session.role, *session.rights);
  } else {
    who = {"modbus " + session.peer, true, "", now_ns < session.unlocked_until_ns};
    if (!policy_.write_clients.empty() &&
        std::find(policy_.write_clients.begin(), policy_.write_clients.end(), session.address) == policy_.write_clients.end())
      who.may_write = false, who.no_write_reason = "client " + session.address + " is not in [modbus] write_clients";
  }
  if (policy_.read_only) who.may_write = false, who.no_write_reason = "the Modbus server is read-only";
  return who;
}

_modbus_mapping_t* new_register_image(const RegisterMap& map) {
  const auto end = [&](Table t) { return static_cast<unsigned>(map.readable_end(t)); };
  return modbus_mapping_new_start_address(0, end(Table::kCoil), 0, end(Table::kDiscreteInput), 0, end(Table::kHoldingRegister), 0,
                                          end(Table::kInputRegister));
}

std::vector<std::uint8_t> tcp_adu(const std::uint8_t* request, std::span<const std::uint8_t> pdu) {
  const std::size_t count = pdu.size() + 1;  // the MBAP length counts the unit id and the PDU
  std::vector<std::uint8_t> adu(kHeader + pdu.size());  // sized first: g++ 12 misreads an insert after a 7-byte list
  adu[0] = request[0], adu[1] = request[1];             // the transaction id; protocol 0
  adu[4] = static_cast<std::uint8_t>(count >> 8), adu[5] = static_cast<std::uint8_t>(count & 0xFF);
  adu[6] = request[6];
  std::copy(pdu.begin(), pdu.end(), adu.begin() + kHeader);
  return adu;
}

}  // namespace epa::modbus
