#include "diag/windowed_gap.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "plant/force_path.hpp"

namespace epa::diag {

double GapSum::rms_mm() const { return n ? std::sqrt(sse_mm2 / static_cast<double>(n)) : 0.0; }

std::size_t first_window_start(const core::HammersteinModel& model) {
  return std::max<std::size_t>({model.A.size(), model.B.size(), 2}) - 1;
}

namespace {

// Where the piston was at sample k by the measurements: the mean of `samples` readings (before
// the run's start, its first reading).
double measured_where_mm(const core::Run& run, std::size_t k, std::size_t samples) {
  double sum = 0.0;
  for (std::size_t i = 0; i < samples; ++i) sum += run.y_mm[k >= i ? k - i : 0];
  return sum / static_cast<double>(samples);
}

struct WindowCount {
  std::size_t replayed = 0, at_end_stop = 0;
};

// Calls on_prediction(k, predicted_mm, error_mm) for every prediction.
template <typename OnPrediction>
WindowCount replay(const ReplayModel& m, const core::Run& run, std::size_t horizon, OnPrediction&& on_prediction) {
  const auto& model = m.model;
  const std::size_t n = run.size();
  const std::size_t start = first_window_start(model);
  if (horizon == 0 || n <= start + 1) return {};
  const std::size_t na = model.A.size() - 1, nb = model.B.size() - 1;
  std::array<double, core::kMaxModelOrder + 1> a{}, b{};
  for (std::size_t i = 0; i <= na; ++i) a[i] = model.A[i];
  for (std::size_t i = 0; i <= nb; ++i) b[i] = model.B[i];
  const double mpv = model.mm_per_volt, max_v = m.stroke_mm / mpv;
  const double step_mm = m.effects.on(plant::EffectKind::kSensorQuantization)
                             ? m.effects.param(plant::EffectKind::kSensorQuantization, 0) : 0.0;

  // The history-dependent input side, once over the whole run: the drive and the force on the
  // piston (friction on the model's mechanical speed, which the command history gives).
  plant::ValveEffects valve(m.effects, model.Ts);
  const auto path = plant::force_path(model);
  plant::DriveEffects drive(m.effects, model.dead_zone, model.Ts, path.speed_mm_s_per_V, path.pole);
  thread_local std::vector<double> pre, force;
  pre.resize(n), force.resize(n);
  for (std::size_t k = 0; k < n; ++k) pre[k] = drive.drive_before_position(valve.apply(run.u_V[k])), force[k] = drive.force();
  const std::size_t nc = path.nc;

  const bool reads_position = drive.reads_position();  // else the replay need not know where the piston is
  const std::size_t where_samples = drive.where_samples();
  // y(k), y(k-1), ... (the model's order, and the positions where the piston is averages); u_d(k), u_d(k-1), ...
  std::array<double, std::max(core::kMaxModelOrder, plant::kMaxWherePositions) + 1> y{}, ud{};
  const std::size_t past = std::max({na, nb, where_samples});  // measured samples a window starts from
  WindowCount count;
  for (std::size_t k0 = start; k0 + 1 < n; k0 += horizon) {
    if (touches_end_stop(run, k0 >= past ? k0 - past : 0, k0 + horizon, m.stroke_mm)) {
      ++count.at_end_stop;
      continue;
    }
    ++count.replayed;
    // y holds the measured past (where_samples of it, for where the piston is), then the model's.
    for (std::size_t i = 0; i < std::max(na, where_samples); ++i) y[i] = run.y_mm[k0 >= i ? k0 - i : 0] / mpv;
    for (std::size_t i = 1; i < nb && i <= k0; ++i)
      ud[i] = drive.finish(pre[k0 - i], reads_position ? measured_where_mm(run, k0 - i, where_samples) : 0.0);
    const std::size_t end = std::min(n - 1, k0 + horizon);
    for (std::size_t k = k0; k < end; ++k) {
      double where_mm = 0.0;
      if (reads_position) {
        for (std::size_t i = 0; i < where_samples; ++i) where_mm += y[i];
        where_mm *= mpv / static_cast<double>(where_samples);
      }
      ud[0] = drive.finish(pre[k], where_mm);
      double next = 0.0;
      for (std::size_t i = 1; i <= na; ++i) next -= a[i] * y[i - 1];
      for (std::size_t i = 1; i <= nb; ++i) next += b[i] * ud[i - 1];
      for (std::size_t i = 1; i <= nc && i <= k + 1; ++i) next += path.c[i] * force[k + 1 - i];
      next = std::clamp(next, 0.0, max_v);
      for (std::size_t i = y.size() - 1; i > 0; --i) y[i] = y[i - 1], ud[i] = ud[i - 1];
      y[0] = next;
      const double predicted_mm = plant::quantize_mm(next * mpv, step_mm);
      on_prediction(k + 1, predicted_mm, predicted_mm - run.y_mm[k + 1]);
    }
  }
  return count;
}

}  // namespace

bool touches_end_stop(const core::Run& run, std::size_t from, std::size_t to, double stroke_mm) {
  for (std::size_t k = from; k <= to && k < run.size(); ++k)
    if (run.y_mm[k] < kEndStopMarginMm || run.y_mm[k] > stroke_mm - kEndStopMarginMm) return true;
  return false;
}

GapSum windowed_sse(const ReplayModel& model, const core::Run& run, std::size_t horizon) {
  GapSum s;
  const auto count = replay(model, run, horizon, [&](std::size_t, double, double e) { s.sse_mm2 += e * e, ++s.n; });
  s.windows = count.replayed, s.windows_at_end_stop = count.at_end_stop;
  return s;
}

WindowedReplay windowed_replay(const ReplayModel& model, const core::Run& run, std::size_t horizon) {
  WindowedReplay r;
  r.k.reserve(run.size()), r.predicted_mm.reserve(run.size()), r.error_mm.reserve(run.size());
  const auto count = replay(model, run, horizon, [&](std::size_t k, double p, double e) {
    r.k.push_back(k), r.predicted_mm.push_back(p), r.error_mm.push_back(e);
    r.sum.sse_mm2 += e * e, ++r.sum.n;
  });
  r.sum.windows = count.replayed, r.sum.windows_at_end_stop = count.at_end_stop;
  return r;
}

double windowed_gap_mm(const ReplayModel& model, std::span<const core::Run* const> runs, std::size_t horizon) {
  GapSum s;
  for (const auto* run : runs) s += windowed_sse(model, *run, horizon);
  return s.rms_mm();
}

}  // namespace epa::diag
