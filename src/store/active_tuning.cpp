#include "store/active_tuning.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"
#include "core/units.hpp"
#include "store/model_table.hpp"
#include "store/tuning_set_table.hpp"

namespace epa::store {

core::Result<LoadedTuning> load_active_tuning(Database& db, std::optional<double> loop_period_s) {
  TuningSetTable sets(db);
  ModelTable models(db);
  auto active = sets.active_id();
  if (!active) return active.error();
  auto last_good = sets.last_good_id();
  if (!last_good) return last_good.error();
  auto all = sets.all();
  if (!all) return all.error();

  // Candidates in order: the active set, the last good one, then the others newest first.
  std::vector<std::int64_t> order;
  if (*active) order.push_back(**active);
  if (*last_good) order.push_back(**last_good);
  for (auto it = all->rbegin(); it != all->rend(); ++it) order.push_back(it->id);

  LoadedTuning out;
  std::vector<std::int64_t> tried;
  for (const std::int64_t id : order) {
    if (std::find(tried.begin(), tried.end(), id) != tried.end()) continue;
    tried.push_back(id);
    auto set = sets.get(id);
    if (!set) {
      out.refused.push_back(set.error().message);
      continue;
    }
    auto model = models.get(set->model_id);
    if (!model) {
      out.refused.push_back("tuning set '" + set->name + "': " + model.error().message);
      continue;
    }
    if (auto s = validate(*set, model->model); !s) {
      out.refused.push_back(s.error().message);
      continue;
    }
    if (loop_period_s && !core::same_sample_time(model->model.Ts, *loop_period_s)) {
      out.refused.push_back("tuning set '" + set->name + "': its model '" + model->name + "' has Ts " +
                            core::format_number(model->model.Ts) + " s, and the loop runs every " +
                            core::format_number(*loop_period_s) + " s (loop.period_s)");
      continue;
    }
    if (!*last_good || **last_good != id)
      if (auto s = sets.set_last_good(id); !s) return s.error();
    out.set = std::move(*set);
    out.model = std::move(*model);
    return out;
  }
  std::string why = "no tuning set in " + db.path() + " validates";
  for (const auto& r : out.refused) why += "; " + r;
  return core::invalid_argument(why);
}

}  // namespace epa::store
