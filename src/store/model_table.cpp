#include "store/model_table.hpp"

#include "core/printable_name.hpp"
#include "store/axis_json.hpp"
#include "store/polynomial_json.hpp"
#include "store/statement.hpp"

namespace epa::store {

namespace {

constexpr const char* kColumns = "id, name, created_ms, source, a_json, b_json, m_r, m_l, b_r, b_l, ts_s, mm_per_volt, fit_json, axis_json";

core::Result<ModelRecord> read_row(const Statement& s) {
  ModelRecord r;
  r.id = s.column_int(0);
  r.name = s.column_text(1);
  r.created_ms = s.column_int(2);
  r.source = s.column_text(3);
  const std::string what = "model " + std::to_string(r.id) + " ('" + r.name + "')";
  auto A = polynomial_from_json_text(s.column_text(4), what + " A");
  if (!A) return A.error();
  auto B = polynomial_from_json_text(s.column_text(5), what + " B");
  if (!B) return B.error();
  r.model.A = *A;
  r.model.B = *B;
  r.model.dead_zone = {s.column_double(6), s.column_double(7), s.column_double(8), s.column_double(9)};
  r.model.Ts = s.column_double(10);
  r.model.mm_per_volt = s.column_double(11);
  r.fit_json = s.column_text(12);
  if (auto st = read_axis_json(s.column_text(13), what, r); !st) return st.error();
  return r;
}

// The same model of the axis: the Hammerstein model and the stick-slip model with what is known of
// them. Two models that differ only in their stick-slip model predict different moves, so one
// must not stand in for the other.
bool same_dynamics(const ModelRecord& a, const ModelRecord& b) {
  const auto &m = a.model, &o = b.model;
  return o.A.coefficients() == m.A.coefficients() && o.B.coefficients() == m.B.coefficients() && o.Ts == m.Ts &&
         o.mm_per_volt == m.mm_per_volt && o.dead_zone.m_r == m.dead_zone.m_r && o.dead_zone.m_l == m.dead_zone.m_l &&
         o.dead_zone.b_r == m.dead_zone.b_r && o.dead_zone.b_l == m.dead_zone.b_l && a.axis_model == b.axis_model &&
         a.identified_drive_v == b.identified_drive_v && a.stick_slip == b.stick_slip && a.stick_slip_spread == b.stick_slip_spread;
}

}  // namespace

core::Result<std::int64_t> ModelTable::insert(const ModelRecord& r) {
  if (r.name.empty()) return core::invalid_argument("a model needs a name");
  // A model's name may be a file's stem (epa design --save): one printable line, as long as a file name.
  if (auto s = core::check_printable_name(r.name, "model name", 255); !s) return s.error();
  if (auto s = r.model.validate(); !s) return core::invalid_argument("model '" + r.name + "': " + s.error().message);
  if (auto s = check_axis_fields(r); !s) return core::invalid_argument("model '" + r.name + "': " + s.error().message);
  auto stmt = db_.prepare(
      "INSERT INTO models (name, created_ms, source, a_json, b_json, m_r, m_l, b_r, b_l, ts_s, mm_per_volt, fit_json, axis_json) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  if (!stmt) return stmt.error();
  const auto& m = r.model;
  stmt->bind(1, r.name).bind(2, r.created_ms).bind(3, r.source).bind(4, to_json_text(m.A)).bind(5, to_json_text(m.B));
  stmt->bind(6, m.dead_zone.m_r).bind(7, m.dead_zone.m_l).bind(8, m.dead_zone.b_r).bind(9, m.dead_zone.b_l);
  stmt->bind(10, m.Ts).bind(11, m.mm_per_volt).bind(12, r.fit_json.empty() ? "{}" : r.fit_json).bind(13, axis_json_text(r));
  if (auto s = stmt->run(); !s) {
    if (db_.last_error_code() == SQLITE_CONSTRAINT_UNIQUE) return core::invalid_argument("a model named '" + r.name + "' exists already");
    return s.error();
  }
  return db_.last_insert_id();
}

core::Result<std::int64_t> ModelTable::find_or_insert(ModelRecord record) {
  auto models = all();
  if (!models) return models.error();
  for (const auto& other : *models)
    if (same_dynamics(other, record)) return other.id;
  const std::string base = record.name;
  for (int n = 2;; ++n) {
    bool taken = false;
    for (const auto& other : *models) taken = taken || other.name == record.name;
    if (!taken) return insert(record);
    record.name = base + " #" + std::to_string(n);
  }
}

core::Result<ModelRecord> ModelTable::get(std::int64_t id) {
  auto stmt = db_.prepare(std::string("SELECT ") + kColumns + " FROM models WHERE id = ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, id);
  auto row = stmt->step();
  if (!row) return row.error();
  if (!*row) return core::invalid_argument("no model with id " + std::to_string(id));
  return read_row(*stmt);
}

core::Result<std::vector<ModelRecord>> ModelTable::all() {
  auto stmt = db_.prepare(std::string("SELECT ") + kColumns + " FROM models ORDER BY id");
  if (!stmt) return stmt.error();
  std::vector<ModelRecord> out;
  auto s = stmt->each_row([&out](const Statement& row) -> core::Status {
    auto r = read_row(row);
    if (!r) return r.error();
    out.push_back(std::move(*r));
    return core::ok();
  });
  if (!s) return s.error();
  return out;
}

}  // namespace epa::store
