#pragma once
// What integrators get from `epa registers`: the validated map as a Markdown table and as CSV,
// with both the 0-based protocol address and the 1-based reference (00001 coils, 10001 discrete
// inputs, 30001 input registers, 40001 holding registers; six digits past 9999), types, word
// order, units and ranges. And the catalog of points a site map can bind.
#include <string>
#include <string_view>

#include "modbus/register_map.hpp"

namespace epa::modbus {

std::string reference_alias(Table table, int address);  // (kHoldingRegister, 0) -> "40001"
// Text for a Markdown table cell: a "|" in it (|target - position|) would end the cell.
std::string markdown_cell(std::string_view text);
std::string export_markdown(const RegisterMap& map);
std::string export_csv(const RegisterMap& map);
std::string points_markdown();

}  // namespace epa::modbus
