#include "app/registers_command.hpp"

#include "app/output_file.hpp"
#include "modbus/register_export.hpp"
#include "modbus/register_map.hpp"

namespace epa::app {

void add_registers_command(CLI::App& app, RegistersOptions& o) {
  auto* cmd = app.add_subcommand("registers", "Validate a Modbus register map and export it for integrators");
  cmd->add_option("map", o.map_path, "Register map file (epa-registers/1 CSV)")->capture_default_str();
  cmd->add_option("--markdown", o.markdown_path, "Write the map as a Markdown table (- for standard output)");
  cmd->add_option("--csv", o.csv_path, "Write the map as CSV with 1-based references (- for standard output)");
  cmd->add_flag("--points", o.points, "List the points a register map can bind");
}

int run_registers(const RegistersOptions& o, std::ostream& out, std::ostream& err) {
  if (o.points) {
    out << modbus::points_markdown();
    return 0;
  }
  auto map = modbus::RegisterMap::load(o.map_path);
  if (!map) return err << "epa registers: " << map.error().message << "\n", 1;
  for (const auto& [path, text] : {std::pair{o.markdown_path, modbus::export_markdown(*map)},
                                   std::pair{o.csv_path, modbus::export_csv(*map)}}) {
    if (path.empty()) continue;
    if (auto s = write_output(path, text, out); !s) return err << "epa registers: " << s.error().message << "\n", 1;
  }
  if (o.markdown_path != "-" && o.csv_path != "-")
    out << o.map_path << ": valid, " << map->entries().size() << " registers\n";
  return 0;
}

}  // namespace epa::app
