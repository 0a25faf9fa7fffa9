#include "app/faults_command.hpp"

#include <cmath>
#include <cstdio>

#include "core/utc_stamp.hpp"
#include "store/fault_table.hpp"
#include "store/store_file.hpp"
#include "web/json_api.hpp"

namespace epa::app {

CLI::App* add_faults_command(CLI::App& app, FaultsOptions& o) {
  auto* cmd = app.add_subcommand("faults", "The fault history from the store, newest first, with each fault's cause");
  cmd->add_option("--store,--db", o.db_path, "The store's database file (epa serve's [store] path)")->capture_default_str();
  cmd->add_flag("--json", o.json, "JSON as GET /api/faults answers it, instead of a table");
  cmd->add_option("--limit", o.limit, "At most this many faults (the store keeps the newest 64)")->capture_default_str();
  return cmd;
}

namespace {

std::string value(double v, const char* format, const char* unit) {
  if (!std::isfinite(v)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, format, v);
  return std::string(text) + " " + unit;
}

}  // namespace

int run_faults(const FaultsOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&err](const std::string& message) { return err << "epa faults: " << message << "\n", 1; };
  auto db = store::open_existing_store(o.db_path);
  if (!db) return fail(db.error().message);
  store::FaultTable table(*db);
  auto faults = table.recent(o.limit);
  if (!faults) return fail(faults.error().message);
  auto count = table.count();
  if (!count) return fail(count.error().message);
  if (o.json) {
    out << web::faults_json(*count, *faults) << "\n";
    return 0;
  }
  out << *count << " fault" << (*count == 1 ? "" : "s") << " since the store was created";
  if (faults->empty()) return out << "\n", 0;
  out << "; the newest " << faults->size() << ", newest first:\n";
  for (const auto& f : *faults) {
    char line[256];
    std::snprintf(line, sizeof line, "%s  %-20s in %-7s position %-10s setpoint %-10s valve %-8s sensor %s\n",
                  core::iso_utc(f.time_ms).c_str(), f.name.c_str(), std::string(runtime::to_string(f.mode)).c_str(),
                  value(f.position_mm, "%.2f", "mm").c_str(), value(f.setpoint_mm, "%.2f", "mm").c_str(),
                  value(f.valve_v, "%.3f", "V").c_str(), value(f.sensor_v, "%.3f", "V").c_str());
    out << line << "    " << f.text << "\n";
  }
  return 0;
}

}  // namespace epa::app
