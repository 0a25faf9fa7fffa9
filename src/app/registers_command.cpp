#include "app/registers_command.hpp"

#include <fstream>

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

namespace {
bool emit(const std::string& path, const std::string& text, std::ostream& out, std::ostream& err) {
  if (path == "-") {
    out << text;
    return true;
  }
  std::ofstream f(path, std::ios::trunc);
  if (!(f << text) || !f.flush()) {
    err << "epa registers: cannot write " << path << "\n";
    return false;
  }
  return true;
}
}  // namespace

int run_registers(const RegistersOptions& o, std::ostream& out, std::ostream& err) {
  if (o.points) {
    out << modbus::points_markdown();
    return 0;
  }
  auto map = modbus::RegisterMap::load(o.map_path);
  if (!map) return err << "epa registers: " << map.error().message << "\n", 1;
  if (!o.markdown_path.empty() && !emit(o.markdown_path, modbus::export_markdown(*map), out, err)) return 1;
  if (!o.csv_path.empty() && !emit(o.csv_path, modbus::export_csv(*map), out, err)) return 1;
  if (o.markdown_path != "-" && o.csv_path != "-")
    out << o.map_path << ": valid, " << map->entries().size() << " registers\n";
  return 0;
}

}  // namespace epa::app
