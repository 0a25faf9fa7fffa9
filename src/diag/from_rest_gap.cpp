#include "diag/from_rest_gap.hpp"

#include <algorithm>
#include <cmath>

#include "plant/hammerstein_plant.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::diag {

namespace {

// The Hammerstein model as the plant simulator runs it, its past positions set at an anchor.
class HammersteinFreeRun {
 public:
  HammersteinFreeRun(const core::HammersteinModel& model, double stroke_mm, double y0_mm)
      : plant_(*plant::HammersteinPlant::make(model, {.initial_position_mm = std::clamp(y0_mm, 0.0, stroke_mm), .stroke_mm = stroke_mm})),
        mm_per_volt_(model.mm_per_volt) {}
  void anchor(double y_mm) {
    auto s = plant_.state();
    s.y_past.fill(y_mm / mm_per_volt_);  // at rest: every past position the same
    plant_.set_state(s);
  }
  double step(double u_V) { return plant_.step(u_V), plant_.position_mm(); }

 private:
  plant::HammersteinPlant plant_;
  double mm_per_volt_;
};

// The stick-slip model, held at the end stops as the cylinder is.
class StickSlipFreeRun {
 public:
  StickSlipFreeRun(const core::StickSlipParams& params, double Ts, double stroke_mm, double y0_mm)
      : model_(*plant::StickSlipModel::make(params, Ts)), stroke_mm_(stroke_mm) {
    model_.reset(y0_mm);
  }
  void anchor(double y_mm) { model_.stop_at(y_mm); }  // the wind-up, spool and delay line stay
  double step(double u_V) {
    const double y = model_.step(u_V);
    if (y < 0.0 || y > stroke_mm_) model_.stop_at(std::clamp(y, 0.0, stroke_mm_));
    return model_.position_mm();
  }
  bool stuck() const { return model_.stuck(); }

 private:
  plant::StickSlipModel model_;
  double stroke_mm_;
};

// Whether the segment's readings from `from` to `to` stay off the end stops and its commands
// inside the identified range.
bool judged(const core::Run& run, std::size_t from, std::size_t to, const JudgedScope& scope) {
  if (touches_end_stop(run, from, to, scope.stroke_mm)) return false;
  for (std::size_t k = from; k <= to && k < run.size(); ++k)
    if (!scope.drive_inside(run.u_V[k])) return false;
  return true;
}

// Runs the model over the whole run; calls on_prediction(k, predicted_mm, model) for each sample counted.
template <class FreeRun, class OnPrediction>
GapSum free_run(FreeRun model, const AnchoredRun& anchored, const JudgedScope& scope, OnPrediction&& on_prediction) {
  const core::Run& run = *anchored.run;
  const auto& anchors = anchored.rests.anchors;
  const std::size_t span = static_cast<std::size_t>(std::lround(scope.span_s / run.Ts));
  GapSum sum;
  std::size_t next = 0;             // the next anchor
  std::size_t counted_until = 0;    // the current segment's last sample (0: none)
  bool counting = false;
  for (std::size_t k = 0; k + 1 < run.size(); ++k) {
    if (next < anchors.size() && anchors[next].k == k) {
      const auto& a = anchors[next];
      const std::size_t end = std::min({next + 1 < anchors.size() ? anchors[next + 1].k : run.size() - 1, k + span, run.size() - 1});
      counting = judged(run, k + 1 - a.readings, end, scope);
      counting ? ++sum.windows : ++sum.windows_at_end_stop;
      counted_until = end;
      model.anchor(a.position_mm);
      ++next;
    }
    const double predicted = model.step(run.u_V[k]);
    if (!counting || k + 1 > counted_until) continue;
    const double e = predicted - run.y_mm[k + 1];
    sum.sse_mm2 += e * e, ++sum.n;
    on_prediction(k + 1, predicted, model);
  }
  return sum;
}

}  // namespace

std::vector<AnchoredRun> anchor_runs(std::span<const core::Run* const> runs) {
  std::vector<AnchoredRun> out;
  for (const auto* run : runs) out.push_back({run, rest_anchors(*run)});
  return out;
}

GapSum from_rest_sse(const core::HammersteinModel& model, const AnchoredRun& run, const JudgedScope& scope) {
  return free_run(HammersteinFreeRun(model, scope.stroke_mm, run.run->y_mm.front()), run, scope, [](std::size_t, double, const auto&) {});
}

GapSum from_rest_sse(const core::StickSlipParams& params, double Ts, const AnchoredRun& run, const JudgedScope& scope) {
  return free_run(StickSlipFreeRun(params, Ts, scope.stroke_mm, run.run->y_mm.front()), run, scope, [](std::size_t, double, const auto&) {});
}

FreeRunTrace from_rest_trace(const core::StickSlipParams& params, double Ts, const AnchoredRun& run, const JudgedScope& scope) {
  FreeRunTrace t;
  t.sum = free_run(StickSlipFreeRun(params, Ts, scope.stroke_mm, run.run->y_mm.front()), run, scope,
                   [&](std::size_t k, double p, const StickSlipFreeRun& m) { t.k.push_back(k), t.predicted_mm.push_back(p), t.stuck.push_back(m.stuck()); });
  return t;
}

FreeRunTrace from_rest_trace(const core::HammersteinModel& model, const AnchoredRun& run, const JudgedScope& scope) {
  FreeRunTrace t;
  t.sum = free_run(HammersteinFreeRun(model, scope.stroke_mm, run.run->y_mm.front()), run, scope,
                   [&](std::size_t k, double p, const HammersteinFreeRun&) { t.k.push_back(k), t.predicted_mm.push_back(p); });
  return t;
}

double from_rest_gap_mm(const core::HammersteinModel& model, std::span<const AnchoredRun> runs, const JudgedScope& scope) {
  GapSum s;
  for (const auto& r : runs) s += from_rest_sse(model, r, scope);
  return s.rms_mm();
}

double from_rest_gap_mm(const core::StickSlipParams& params, double Ts, std::span<const AnchoredRun> runs, const JudgedScope& scope) {
  GapSum s;
  for (const auto& r : runs) s += from_rest_sse(params, Ts, r, scope);
  return s.rms_mm();
}

double from_rest_noise_floor_mm(std::span<const AnchoredRun> runs, double noise_std_mm) {
  double inverse_readings = 0.0;  // the mean of 1 / readings over every anchor
  std::size_t anchors = 0;
  for (const auto& r : runs)
    for (const auto& a : r.rests.anchors) inverse_readings += 1.0 / static_cast<double>(a.readings), ++anchors;
  if (anchors > 0) inverse_readings /= static_cast<double>(anchors);
  return noise_std_mm * std::sqrt(1.0 + inverse_readings);
}

}  // namespace epa::diag
