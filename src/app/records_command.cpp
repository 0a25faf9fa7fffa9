#include "app/records_command.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "app/appliance_http.hpp"
#include "points/point_catalog.hpp"
#include "points/point_id.hpp"
#include "web/json_api.hpp"

namespace epa::app {

CLI::App* add_records_command(CLI::App& app, RecordsOptions& o) {
  auto* cmd = app.add_subcommand("records", "The position-record table of a running appliance: list it, or set a record's fields");
  cmd->fallthrough();  // --url after `set` too
  cmd->add_option("--url", o.url, "The appliance's status page, http://HOST:PORT")->capture_default_str();
  cmd->add_flag("--json", o.json, "The JSON of GET /api/records instead of a table");
  auto* set = cmd->add_subcommand("set", "Write the given fields of record N in one request (the [web] token needed)");
  set->add_option("record", o.record, "The record, 1.." + std::to_string(points::kPositionRecords))
      ->required()
      ->check(CLI::Range(1, static_cast<int>(points::kPositionRecords)));
  set->add_option("--target-mm", o.target_mm, "Target position, mm (within the appliance's setpoint range)");
  set->add_option("--speed-mm-s", o.speed_mm_s, "Speed limit, mm/s (0: none, the law's own step response)");
  set->add_option("--window-mm", o.window_mm, "In-position window, mm (0: [motion] in_position_window_mm)");
  set->add_option("--controller", o.controller, "The law: pp, pp-ngidz, pp-ffidz, pp-traj, or running (the one running then)");
  set->add_option("--approach", o.approach,
                  "The side pp-traj's sliding arrival comes from: near (never past the target), from-below or from-above");
  set->add_option("--token", o.token, "The appliance's [web] token; shows in ps: prefer EPA_TOKEN or --token-file")->envname("EPA_TOKEN");
  set->add_option("--token-file", o.token_file, "A file whose first line is the appliance's [web] token");
  set->callback([&o] { o.set = true; });
  return cmd;
}

namespace {

std::string number(const nlohmann::json& v, const char* format, const char* zero) {
  if (!v.is_number()) return "-";
  const double x = v.get<double>();
  if (x == 0.0 && zero) return zero;
  char text[32];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

void print_row(const nlohmann::json& r, std::ostream& out) {
  char line[160];
  using K = web::RecordKeys;
  std::snprintf(line, sizeof line, "%6d  %10s  %16s  %9s  %-8s  %s\n", r.value(K::kRecord, 0), number(r[K::kTarget], "%.3f", nullptr).c_str(),
                number(r[K::kSpeed], "%.3f", "no limit").c_str(), number(r[K::kWindow], "%.3f", "default").c_str(),
                r.value(K::kController, std::string("-")).c_str(), r.value(K::kApproach, std::string("-")).c_str());
  out << line;
}
constexpr const char* kHead = "record   target mm  speed limit mm/s  window mm  law       approach\n";

}  // namespace

int run_records(const RecordsOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&err](const std::string& m) { return err << "epa records: " << m << "\n", 1; };
  auto made = appliance_client(o.url);
  if (!made) return fail(made.error().message);
  httplib::Client& client = **made;

  if (o.set) {
    using K = web::RecordKeys;
    nlohmann::json body = {{K::kRecord, o.record}};
    if (o.target_mm) body[K::kTarget] = *o.target_mm;
    if (o.speed_mm_s) body[K::kSpeed] = *o.speed_mm_s;
    if (o.window_mm) body[K::kWindow] = *o.window_mm;
    if (o.controller) body[K::kController] = *o.controller;
    if (o.approach) body[K::kApproach] = *o.approach;
    if (body.size() == 1)
      return fail("record " + std::to_string(o.record) + ": nothing to set: give --target-mm, --speed-mm-s, --window-mm, --controller or --approach");
    const auto token = appliance_token(o.token, o.token_file);
    if (!token) return fail("record " + std::to_string(o.record) + ": " + token.error().message);
    for (const char* f : {K::kTarget, K::kSpeed, K::kWindow})
      if (body.contains(f) && !std::isfinite(body[f].get<double>())) return fail(std::string(f) + " must be a finite number");
    auto r = client.Post("/api/records", bearer(*token), body.dump(), "application/json");
    if (!r) return fail("record " + std::to_string(o.record) + ": " + http_failure(r, o.url));
    if (r->status != 200) return fail("the appliance refused record " + std::to_string(o.record) + ": " + http_failure(r, o.url));
  }
  auto r = client.Get("/api/records");
  if (!r || r->status != 200) return fail("the record table: " + http_failure(r, o.url));
  const auto table = nlohmann::json::parse(r->body, nullptr, false);
  if (!table.is_object() || !table.contains("records") || !table["records"].is_array())
    return fail(o.url + "/api/records did not answer a record table (an older appliance?)");
  if (o.set) {
    out << "record " << o.record << " set; the appliance now holds:\n" << kHead;
    for (const auto& rec : table["records"])
      if (rec.value("record", 0) == o.record) print_row(rec, out);
    return 0;
  }
  if (o.json) return out << r->body << "\n", 0;
  out << kHead;
  for (const auto& rec : table["records"]) print_row(rec, out);
  const std::string record_select(points::name(points::PointId::kRecordSelect));
  const int selected = table.value(record_select, 0);
  out << record_select << ": " << selected << (selected == 0 ? " (a start moves to setpoint_mm)" : "") << "\n";
  return 0;
}

}  // namespace epa::app
