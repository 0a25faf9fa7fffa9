#include "app/tuning_command.hpp"

#include <cmath>
#include <ctime>
#include <nlohmann/json.hpp>

#include "app/output_file.hpp"
#include "control/branch_stability.hpp"
#include "core/format.hpp"
#include "core/model_file.hpp"
#include "core/printable_name.hpp"
#include "core/text_file.hpp"
#include "core/utc_stamp.hpp"
#include "store/audit_log.hpp"
#include "store/model_table.hpp"
#include "store/run_table.hpp"
#include "store/set_activation.hpp"
#include "store/store_file.hpp"
#include "store/trajectory_settings.hpp"
#include "store/transaction.hpp"
#include "store/tuning_file.hpp"
#include "store/tuning_set_table.hpp"

namespace epa::app {

void add_tuning_command(CLI::App& app, TuningOptions& o) {
  auto* cmd = app.add_subcommand("tuning", "The tuning store: list, show, diff, activate, export, import, audit, runs");
  cmd->require_subcommand(1);
  cmd->add_option("--db", o.db_path, "The store's database file (epa serve's [store] path)")->capture_default_str();
  cmd->add_subcommand("list", "Tuning sets, the active one marked with *");
  cmd->add_subcommand("show", "One tuning set with its model")->add_option("set", o.set, "Id or name")->required();
  auto* diff = cmd->add_subcommand("diff", "What differs between two tuning sets");
  diff->add_option("a", o.set, "Id or name")->required();
  diff->add_option("b", o.other, "Id or name")->required();
  cmd->add_subcommand("activate", "Make a set the active one (used from the appliance's next start)")
      ->add_option("set", o.set, "Id or name")->required();
  auto* exp = cmd->add_subcommand("export", "Write a set and its model as an epa-tuning/1 TOML file");
  exp->add_option("set", o.set, "Id or name")->required();
  exp->add_option("--out", o.file, "File to write ('-': standard output)")->required();
  auto* imp = cmd->add_subcommand("import", "Read an epa-tuning/1 TOML file into the store as a new set");
  imp->add_option("file", o.file, "epa-tuning/1 file")->required()->check(CLI::ExistingFile);
  imp->add_option("--name", o.name, "Name of the new set (default: the file's)");
  imp->add_flag("--activate", o.activate, "Make it the active set");
  auto* audit = cmd->add_subcommand("audit", "The audit log, newest first");
  audit->add_option("--since", o.since, "From this time on: YYYY-MM-DD, YYYY-MM-DDThh:mm:ssZ (UTC) or unix ms");
  audit->add_option("--until", o.until, "Up to this time (same forms)");
  audit->add_option("--source", o.source, "Only sources containing this text (modbus, web, cli, an address)");
  audit->add_option("--point", o.point, "Only this point (setpoint_mm, m_r, ...)");
  audit->add_option("--limit", o.limit, "At most this many entries (0: all)")->capture_default_str();
  audit->add_flag("--json", o.json, "JSON lines instead of a table");
  cmd->add_subcommand("runs", "The run history, newest first")->add_option("--limit", o.limit, "At most this many")->capture_default_str();
}

namespace {

std::string iso_time(std::int64_t ms) { return core::iso_utc(ms); }

// YYYY-MM-DD, YYYY-MM-DDThh:mm:ssZ (UTC) or unix milliseconds.
core::Result<std::int64_t> parse_time(const std::string& text, const char* option) {
  if (!text.empty() && text.find_first_not_of("0123456789") == std::string::npos) return std::stoll(text);
  std::tm tm{};
  const char* end = strptime(text.c_str(), "%Y-%m-%dT%H:%M:%S", &tm);
  if (!end) {
    tm = {};
    end = strptime(text.c_str(), "%Y-%m-%d", &tm);
  }
  if (!end || !(*end == '\0' || (end[0] == 'Z' && end[1] == '\0')))
    return core::invalid_argument(std::string(option) + " '" + text + "' is not a time: use YYYY-MM-DD, YYYY-MM-DDThh:mm:ssZ or unix ms");
  return static_cast<std::int64_t>(timegm(&tm)) * 1000;
}

std::string poly_text(const core::Polynomial& p) {
  std::string s = "[";
  for (std::size_t i = 0; i < p.size(); ++i) s += (i ? ", " : "") + core::format_number(p[i]);
  return s + "]";
}

// Where a set came from, and whether its values were edited since (Modbus or HTTP writes: the
// store moves its modified time, and the audit trail has each edit from its creation on).
std::string source_text(const store::TuningSet& t) {
  if (t.modified_ms <= t.created_ms) return t.source;
  return t.source + "; edited since (the edits: epa tuning audit --since " + std::to_string(t.created_ms) + ")";
}

// Whether the set's model has a stick-slip model, and which of the two describes the axis.
std::string stick_slip_text(const store::ModelRecord& m) {
  return m.stick_slip ? "yes (axis_model " + std::string(core::to_string(m.axis_model)) + ")" : "none";
}

// Field name and value, in the order `show` prints and `diff` compares them.
std::vector<std::pair<std::string, std::string>> fields(const store::TuningSet& t, const store::ModelRecord& m) {
  std::vector<std::pair<std::string, std::string>> out = {{"name", t.name},
          {"source", source_text(t)},
          {"created", iso_time(t.created_ms)},
          {"modified", iso_time(t.modified_ms)},
          {"controller", std::string(control::to_string(t.controller))},
          {"F", poly_text(t.F)},
          {"G", poly_text(t.G)},
          {"H", poly_text(t.H)},
          {"dead_zone m_r", core::format_number(t.dead_zone.m_r)},
          {"dead_zone m_l", core::format_number(t.dead_zone.m_l)},
          {"dead_zone b_r V", core::format_number(t.dead_zone.b_r)},
          {"dead_zone b_l V", core::format_number(t.dead_zone.b_l)},
          {"lc_mm", core::format_number(t.lc_mm)},
          {"valve_limit_v", core::format_number(t.valve_limit_v)},
          {"design", t.design_json}};
  for (const auto& [key, value] : store::trajectory_setting_values(t.trajectory))  // pp-traj's own parameters
    out.emplace_back("pp-traj " + key, core::format_number(value));
  const std::pair<std::string, std::string> model_fields[] = {
      {"model", m.name + " (id " + std::to_string(m.id) + ")"},
      {"model source", m.source},
      {"model A", poly_text(m.model.A)},
      {"model B", poly_text(m.model.B)},
      {"model Ts s", core::format_number(m.model.Ts)},
      {"model mm_per_volt", core::format_number(m.model.mm_per_volt)},
      {"stick-slip model", stick_slip_text(m)},
      {"model fit", m.fit_json}};
  out.insert(out.end(), std::begin(model_fields), std::end(model_fields));
  return out;
}

// The branches of A F + gain B G that are unstable, on the file's model with its dead zone and,
// when the set's own dead zone differs (what NG-IDZ and FF-IDZ invert), with that one too.
std::string unstable_branches_of(const store::TuningFile& file) {
  const core::HammersteinModel& model = file.model.model;
  std::string unstable = control::unstable_branches(control::analyse_branches(model, file.set.F, file.set.G));
  const auto& dz = file.set.dead_zone;
  if (dz.m_l == model.dead_zone.m_l && dz.m_r == model.dead_zone.m_r) return unstable;
  core::HammersteinModel with_set_dead_zone = model;
  with_set_dead_zone.dead_zone = dz;
  const std::string also = control::unstable_branches(control::analyse_branches(with_set_dead_zone, file.set.F, file.set.G));
  if (also.empty()) return unstable;
  return unstable + (unstable.empty() ? "" : "; ") + also + " with the set's dead zone";
}

std::string number_or_dash(const std::optional<double>& v) { return v ? core::format_number(*v) : "-"; }

int tuning_failed(std::ostream& err, const std::string& message) { return err << "epa tuning: " << message << "\n", 1; }

// One subcommand: the store, the options, where it prints. Errors it returns print as
// "epa tuning: ..." with exit 1; a store error it cannot return is thrown.
using Subcommand = int (*)(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err);

int list_subcommand(store::Database& db, const TuningOptions&, std::ostream& out, std::ostream&) {
  auto sets = store::TuningSetTable(db).all();
  if (!sets) throw std::runtime_error(sets.error().message);
  auto active = store::TuningSetTable(db).active_id();
  if (!active) throw std::runtime_error(active.error().message);
  out << "   id  name                  controller  modified                   source\n";
  for (const auto& t : *sets) {
    char line[512];
    std::snprintf(line, sizeof line, "%s %3lld  %-20s  %-10s  %-25s  %s\n", *active && **active == t.id ? "*" : " ",
                  static_cast<long long>(t.id), t.name.c_str(), std::string(control::to_string(t.controller)).c_str(),
                  iso_time(t.modified_ms).c_str(), source_text(t).c_str());
    out << line;
  }
  return 0;
}

int show_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto s = store::find_set_with_model(db, o.set);
  if (!s) return tuning_failed(err, s.error().message);
  auto active = store::TuningSetTable(db).active_id();
  out << "tuning set " << s->set.id << (active && *active && **active == s->set.id ? " (active)" : "") << "\n";
  for (const auto& [k, v] : fields(s->set, s->model)) out << "  " << k << ": " << v << "\n";
  return 0;
}

int diff_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto a = store::find_set_with_model(db, o.set);
  if (!a) return tuning_failed(err, a.error().message);
  auto b = store::find_set_with_model(db, o.other);
  if (!b) return tuning_failed(err, b.error().message);
  const auto fa = fields(a->set, a->model), fb = fields(b->set, b->model);
  int differences = 0;
  for (std::size_t i = 0; i < fa.size(); ++i) {
    const std::string& key = fa[i].first;  // identity and history are not values
    if (key == "name" || key == "source" || key == "created" || key == "modified" || fa[i].second == fb[i].second) continue;
    out << fa[i].first << ":\n  " << a->set.name << ": " << fa[i].second << "\n  " << b->set.name << ": " << fb[i].second << "\n";
    ++differences;
  }
  if (differences == 0) out << "'" << a->set.name << "' and '" << b->set.name << "' have the same values\n";
  return 0;
}

int activate_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto s = store::find_set_with_model(db, o.set);
  if (!s) return tuning_failed(err, s.error().message);
  auto tx = store::Transaction::begin(db);
  if (!tx) return tuning_failed(err, tx.error().message);
  if (auto st = store::activate_audited(db, s->set.id, "cli"); !st) return tuning_failed(err, st.error().message);
  if (auto st = tx->commit(); !st) return tuning_failed(err, st.error().message);
  out << "tuning set '" << s->set.name << "' (id " << s->set.id << ") is active: a running appliance uses it from its next start\n";
  return 0;
}

int export_set_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto s = store::find_set_with_model(db, o.set);
  if (!s) return tuning_failed(err, s.error().message);
  if (auto st = write_output(o.file, store::format_tuning_toml(s->set, s->model), out); !st) return tuning_failed(err, st.error().message);
  if (o.file != "-") out << "tuning set '" << s->set.name << "' written to " << o.file << "\n";
  return 0;
}

// The file's set with its model (reused when already stored), audited, in the transaction of the
// caller; activated when asked. Returns the set's id.
core::Result<std::int64_t> insert_imported(store::Database& db, store::TuningFile& file, const TuningOptions& o) {
  file.model.created_ms = core::unix_time_ms();
  auto model_id = store::ModelTable(db).find_or_insert(file.model);
  if (!model_id) return model_id.error();
  file.set.model_id = *model_id;
  file.set.created_ms = file.set.modified_ms = core::unix_time_ms();
  file.set.source = "imported from " + o.file + (file.set.source.empty() ? "" : " (" + file.set.source + ")");
  auto id = store::TuningSetTable(db).insert(file.set);
  if (!id) return core::Error{id.error().code, id.error().message + (o.name.empty() ? " (give another with --name)" : "")};
  if (auto st = store::AuditLog(db).append({core::unix_time_ms(), "cli", "import_tuning_set", std::nan(""), static_cast<double>(*id)}); !st)
    return st.error();
  if (o.activate)
    if (auto st = store::activate_audited(db, *id, "cli"); !st) return st.error();
  return id;
}

int import_set_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto text = core::read_text_file(o.file, "tuning file", core::kSmallFileCapBytes);
  if (!text) return tuning_failed(err, text.error().message);
  auto file = store::parse_tuning_toml(*text, o.file);
  if (!file) return tuning_failed(err, file.error().message);
  if (!o.name.empty()) file->set.name = o.name;
  if (auto st = core::check_printable_name(file->set.name, "--name"); !st) return tuning_failed(err, st.error().message);
  // The set runs on the axis once active: it passes the same Jury test as `epa design --save`.
  if (const auto unstable = unstable_branches_of(*file); !unstable.empty()) {
    err << "epa tuning: import refused: tuning set '" << file->set.name << "' of " << o.file
        << " is UNSTABLE: the closed loop is unstable on " << unstable
        << "; a controller with this set does not hold the axis there (epa design shows each branch's Jury table)\n";
    return 3;
  }
  auto tx = store::Transaction::begin(db);
  if (!tx) return tuning_failed(err, tx.error().message);
  auto id = insert_imported(db, *file, o);
  if (!id) return tuning_failed(err, id.error().message);
  if (auto st = tx->commit(); !st) return tuning_failed(err, st.error().message);
  out << "imported tuning set '" << file->set.name << "' (id " << *id << ")" << (o.activate ? ", active from the appliance's next start" : "") << "\n";
  return 0;
}

core::Result<store::AuditFilter> audit_filter(const TuningOptions& o) {
  store::AuditFilter f;
  if (!o.since.empty()) {
    auto t = parse_time(o.since, "--since");
    if (!t) return t.error();
    f.since_ms = *t;
  }
  if (!o.until.empty()) {
    auto t = parse_time(o.until, "--until");
    if (!t) return t.error();
    f.until_ms = *t;
  }
  f.source = o.source;
  f.point = o.point;
  f.limit = o.limit;
  return f;
}

void print_audit_row(const store::AuditRecord& r, bool json, std::ostream& out) {
  const auto& e = r.entry;
  if (json) {
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    out << nlohmann::json{{"id", r.id}, {"time", iso_time(e.unix_time_ms)}, {"unix_time_ms", e.unix_time_ms},
                          {"source", e.source}, {"point", e.point}, {"old", num(e.old_value)}, {"new", num(e.new_value)}}
               .dump()
        << "\n";
  } else {
    out << iso_time(e.unix_time_ms) << "  " << e.source << "  " << e.point << "  "
        << (core::is_audit_event(e) ? "nothing changed"
                                    : core::audit_value_text(e.old_value) + " -> " + core::audit_value_text(e.new_value))
        << "\n";
  }
}

int audit_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto f = audit_filter(o);
  if (!f) return tuning_failed(err, f.error().message);
  auto rows = store::AuditLog(db).query(*f);
  if (!rows) return tuning_failed(err, rows.error().message);
  for (const auto& r : *rows) print_audit_row(r, o.json, out);
  if (!o.json && rows->empty()) out << "no audit entries match\n";
  return 0;
}

int runs_subcommand(store::Database& db, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  auto recent = store::RunTable(db).recent(o.limit);
  if (!recent) return tuning_failed(err, recent.error().message);
  for (const auto& r : *recent)
    out << iso_time(r.recorded_ms) << "  " << r.controller << "  " << number_or_dash(r.from_mm) << " -> "
        << number_or_dash(r.to_mm) << " mm  rise " << number_or_dash(r.rise_s) << " s  settling "
        << number_or_dash(r.settling_s) << " s  e_ss " << number_or_dash(r.ess_mm) << " mm  overshoot "
        << number_or_dash(r.overshoot_pct) << " %  " << r.path << "\n";
  if (recent->empty()) out << "no runs recorded\n";
  return 0;
}

}  // namespace

int run_tuning(CLI::App& app, const TuningOptions& o, std::ostream& out, std::ostream& err) {
  const std::pair<const char*, Subcommand> subcommands[] = {{"list", list_subcommand},         {"show", show_subcommand},     {"diff", diff_subcommand},
                                                            {"activate", activate_subcommand}, {"export", export_set_subcommand}, {"import", import_set_subcommand},
                                                            {"audit", audit_subcommand},       {"runs", runs_subcommand}};
  auto* cmd = app.get_subcommand("tuning");
  auto db = store::open_existing_store(o.db_path);
  if (!db) return tuning_failed(err, db.error().message);
  try {
    for (const auto& [name, run] : subcommands)
      if (cmd->got_subcommand(name)) return run(*db, o, out, err);
  } catch (const std::exception& e) {
    return tuning_failed(err, e.what());
  }
  return tuning_failed(err, "unknown subcommand");
}

}  // namespace epa::app
