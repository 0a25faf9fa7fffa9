#include "modbus/read_answer.hpp"

#include <modbus.h>

namespace epa::modbus {

namespace {
int word_at(const std::uint8_t* p) { return (p[0] << 8) | p[1]; }  // big-endian, as Modbus sends them
}  // namespace

std::optional<std::vector<std::uint8_t>> read_answer(const std::uint8_t* pdu, int length, const _modbus_mapping_t* image) {
  if (length < 5) return std::nullopt;
  const int fc = pdu[0], address = word_at(pdu + 1), quantity = word_at(pdu + 3);
  const bool bits = fc == MODBUS_FC_READ_COILS || fc == MODBUS_FC_READ_DISCRETE_INPUTS;
  const bool words = fc == MODBUS_FC_READ_HOLDING_REGISTERS || fc == MODBUS_FC_READ_INPUT_REGISTERS;
  if (!bits && !words) return std::nullopt;
  const int start = bits ? (fc == MODBUS_FC_READ_COILS ? image->start_bits : image->start_input_bits)
                         : (fc == MODBUS_FC_READ_HOLDING_REGISTERS ? image->start_registers : image->start_input_registers);
  const int count = bits ? (fc == MODBUS_FC_READ_COILS ? image->nb_bits : image->nb_input_bits)
                         : (fc == MODBUS_FC_READ_HOLDING_REGISTERS ? image->nb_registers : image->nb_input_registers);
  const int max = bits ? MODBUS_MAX_READ_BITS : MODBUS_MAX_READ_REGISTERS;
  if (quantity < 1 || quantity > max || address < start || address - start + quantity > count) return std::nullopt;
  const int first = address - start;
  std::vector<std::uint8_t> out = {static_cast<std::uint8_t>(fc)};
  if (words) {
    const std::uint16_t* table = fc == MODBUS_FC_READ_HOLDING_REGISTERS ? image->tab_registers : image->tab_input_registers;
    out.push_back(static_cast<std::uint8_t>(2 * quantity));
    for (int i = 0; i < quantity; ++i) {
      out.push_back(static_cast<std::uint8_t>(table[first + i] >> 8));
      out.push_back(static_cast<std::uint8_t>(table[first + i] & 0xFF));
    }
    return out;
  }
  // Bits, least significant first in each byte, as the specification packs them.
  const std::uint8_t* table = fc == MODBUS_FC_READ_COILS ? image->tab_bits : image->tab_input_bits;
  out.push_back(static_cast<std::uint8_t>((quantity + 7) / 8));
  for (int i = 0; i < quantity; i += 8) {
    std::uint8_t byte = 0;
    for (int b = 0; b < 8 && i + b < quantity; ++b) byte |= static_cast<std::uint8_t>((table[first + i + b] ? 1 : 0) << b);
    out.push_back(byte);
  }
  return out;
}

}  // namespace epa::modbus
