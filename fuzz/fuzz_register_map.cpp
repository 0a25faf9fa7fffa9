// Register-map CSV text (registers/*.csv, epa-registers/1) into the parser the appliance runs at
// start-up: every input must give a map or an error naming a line, never a crash. A map that
// parses must answer find() consistently for every address of every table.
#include <cstddef>
#include <cstdint>
#include <string>

#include "modbus/register_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace epa::modbus;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto map = RegisterMap::parse(text, "fuzz.csv");
  if (!map) return 0;
  for (Table t : {Table::kCoil, Table::kDiscreteInput, Table::kInputRegister, Table::kHoldingRegister}) {
    for (int a = -1; a <= map->end_address(t); ++a) {
      const auto hit = map->find(t, a);
      if (!hit.entry) continue;
      // A hit lies inside its entry and the entry round-trips a value through its codec.
      if (hit.entry->table != t || hit.offset < 0 || hit.offset >= hit.entry->width()) __builtin_trap();
      std::uint16_t words[2] = {};
      encode_value(*hit.entry, hit.entry->min, words);
      (void)decode_value(*hit.entry, words);
    }
  }
  return 0;
}
