#include "store/tuning_set_table.hpp"

#include <charconv>

#include "core/printable_name.hpp"
#include "store/polynomial_json.hpp"
#include "store/statement.hpp"

namespace epa::store {

namespace {

constexpr const char* kColumns =
    "id, name, created_ms, modified_ms, source, model_id, controller, f_json, g_json, h_json, design_json, "
    "m_r, m_l, b_r, b_l, lc_mm, valve_limit_v, trajectory_json";

core::Result<TuningSet> read_row(const Statement& s) {
  TuningSet t;
  t.id = s.column_int(0);
  t.name = s.column_text(1);
  t.created_ms = s.column_int(2);
  t.modified_ms = s.column_int(3);
  t.source = s.column_text(4);
  t.model_id = s.column_int(5);
  const std::string what = "tuning set " + std::to_string(t.id) + " ('" + t.name + "')";
  auto kind = control::parse_controller_kind(s.column_text(6));
  if (!kind) return core::parse_error(what + ": " + kind.error().message);
  t.controller = *kind;
  core::Polynomial* polys[] = {&t.F, &t.G, &t.H};
  const char* names[] = {" F", " G", " H"};
  for (int i = 0; i < 3; ++i) {
    auto p = polynomial_from_json_text(s.column_text(7 + i), what + names[i]);
    if (!p) return p.error();
    *polys[i] = *p;
  }
  t.design_json = s.column_text(10);
  t.dead_zone = {s.column_double(11), s.column_double(12), s.column_double(13), s.column_double(14)};
  t.lc_mm = s.column_double(15);
  t.valve_limit_v = s.column_double(16);
  auto trajectory = trajectory_settings_from_json_text(s.column_text(17), what + " trajectory_json");
  if (!trajectory) return trajectory.error();
  t.trajectory = *trajectory;
  return t;
}

void bind_values(Statement& s, const TuningSet& t) {
  s.bind(1, t.name).bind(2, t.modified_ms).bind(3, t.source).bind(4, t.model_id);
  s.bind(5, std::string(control::to_string(t.controller)));
  s.bind(6, to_json_text(t.F)).bind(7, to_json_text(t.G)).bind(8, to_json_text(t.H)).bind(9, t.design_json.empty() ? "{}" : t.design_json);
  s.bind(10, t.dead_zone.m_r).bind(11, t.dead_zone.m_l).bind(12, t.dead_zone.b_r).bind(13, t.dead_zone.b_l);
  s.bind(14, t.lc_mm).bind(15, t.valve_limit_v).bind(16, to_json_text(t.trajectory));
}

core::Result<std::vector<TuningSet>> read_all(Statement& stmt) {
  std::vector<TuningSet> out;
  auto s = stmt.each_row([&out](const Statement& row) -> core::Status {
    auto t = read_row(row);
    if (!t) return t.error();
    out.push_back(std::move(*t));
    return core::ok();
  });
  if (!s) return s.error();
  return out;
}

}  // namespace

core::Result<std::int64_t> TuningSetTable::insert(const TuningSet& t) {
  if (t.name.empty()) return core::invalid_argument("a tuning set needs a name");
  // Every way in (import, design --save, commissioning) passes here: a name reaches the log and `tuning list`.
  if (auto s = core::check_printable_name(t.name, "tuning set name"); !s) return s.error();
  auto stmt = db_.prepare(
      "INSERT INTO tuning_sets (name, modified_ms, source, model_id, controller, f_json, g_json, h_json, design_json, "
      "m_r, m_l, b_r, b_l, lc_mm, valve_limit_v, trajectory_json, created_ms) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  if (!stmt) return stmt.error();
  bind_values(*stmt, t);
  stmt->bind(17, t.created_ms);
  if (auto s = stmt->run(); !s) {
    const int code = db_.last_error_code();
    if (code == SQLITE_CONSTRAINT_UNIQUE) return core::invalid_argument("a tuning set named '" + t.name + "' exists already");
    if (code == SQLITE_CONSTRAINT_FOREIGNKEY)
      return core::invalid_argument("tuning set '" + t.name + "' names model " + std::to_string(t.model_id) + ", which does not exist");
    return s.error();
  }
  return db_.last_insert_id();
}

core::Result<TuningSet> TuningSetTable::get(std::int64_t id) {
  auto stmt = db_.prepare(std::string("SELECT ") + kColumns + " FROM tuning_sets WHERE id = ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, id);
  auto rows = read_all(*stmt);
  if (!rows) return rows.error();
  if (rows->empty()) return core::invalid_argument("no tuning set with id " + std::to_string(id));
  return std::move(rows->front());
}

core::Result<TuningSet> TuningSetTable::find(const std::string& key) {
  std::int64_t id = 0;
  const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), id);
  if (ec == std::errc() && end == key.data() + key.size()) return get(id);
  auto stmt = db_.prepare(std::string("SELECT ") + kColumns + " FROM tuning_sets WHERE name = ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, key);
  auto rows = read_all(*stmt);
  if (!rows) return rows.error();
  if (rows->empty()) return core::invalid_argument("no tuning set named '" + key + "' (epa tuning list shows them)");
  return std::move(rows->front());
}

core::Result<std::vector<TuningSet>> TuningSetTable::all() {
  auto stmt = db_.prepare(std::string("SELECT ") + kColumns + " FROM tuning_sets ORDER BY id");
  if (!stmt) return stmt.error();
  return read_all(*stmt);
}

core::Status TuningSetTable::update(const TuningSet& t) {
  auto stmt = db_.prepare(
      "UPDATE tuning_sets SET name = ?, modified_ms = ?, source = ?, model_id = ?, controller = ?, f_json = ?, g_json = ?, "
      "h_json = ?, design_json = ?, m_r = ?, m_l = ?, b_r = ?, b_l = ?, lc_mm = ?, valve_limit_v = ?, trajectory_json = ? WHERE id = ?");
  if (!stmt) return stmt.error();
  bind_values(*stmt, t);
  stmt->bind(17, t.id);
  if (auto s = stmt->run(); !s) return s;
  if (db_.changes() != 1) return core::invalid_argument("no tuning set with id " + std::to_string(t.id));
  return core::ok();
}

core::Status TuningSetTable::activate(std::int64_t id) {
  if (auto t = get(id); !t) return t.error();
  return put_setting("active_tuning_set", id);
}

core::Result<std::optional<std::int64_t>> TuningSetTable::active_id() { return setting("active_tuning_set"); }
core::Status TuningSetTable::set_last_good(std::int64_t id) { return put_setting("last_good_tuning_set", id); }
core::Result<std::optional<std::int64_t>> TuningSetTable::last_good_id() { return setting("last_good_tuning_set"); }

core::Status TuningSetTable::put_setting(const std::string& key, std::int64_t value) {
  auto stmt = db_.prepare("INSERT INTO settings (key, value) VALUES (?, ?) ON CONFLICT(key) DO UPDATE SET value = excluded.value");
  if (!stmt) return stmt.error();
  stmt->bind(1, key).bind(2, std::to_string(value));
  return stmt->run();
}

core::Result<std::optional<std::int64_t>> TuningSetTable::setting(const std::string& key) {
  auto stmt = db_.prepare("SELECT value FROM settings WHERE key = ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, key);
  auto row = stmt->step();
  if (!row) return row.error();
  if (!*row) return std::optional<std::int64_t>{};
  const std::string text = stmt->column_text(0);
  std::int64_t id = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), id);
  if (ec != std::errc() || end != text.data() + text.size())
    return core::parse_error("setting " + key + " = '" + text + "' is not a tuning set id");
  return std::optional<std::int64_t>(id);
}

}  // namespace epa::store
