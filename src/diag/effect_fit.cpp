#include "diag/effect_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlopt.hpp>

namespace epa::diag {

namespace {

using plant::EffectKind;

// One free parameter: which effect and slot, and how it maps to [0, 1] for the optimiser
// (logarithmic where its spec says so: a range of decades).
struct Slot {
  EffectKind kind;
  std::size_t i;
  plant::ParamSpec spec;
  bool fresh = true;  // the effect was off in the base model: search its range from several starts
  bool log_scale() const { return spec.log_scale; }
  double to_unit(double v) const {
    return log_scale() ? std::log(v / spec.lo) / std::log(spec.hi / spec.lo) : (v - spec.lo) / (spec.hi - spec.lo);
  }
  double from_unit(double x) const {
    x = std::clamp(x, 0.0, 1.0);
    return log_scale() ? spec.lo * std::pow(spec.hi / spec.lo, x) : spec.lo + x * (spec.hi - spec.lo);
  }
};

struct Objective {
  ReplayModel model;
  std::span<const core::Run* const> runs;
  std::size_t horizon;
  std::size_t evaluations = 0;
  double gap() {
    ++evaluations;
    GapSum s;
    for (const auto* r : runs) s += windowed_sse(model, *r, horizon);
    return s.rms_mm();
  }
};

void put(ReplayModel& m, const Slot& s, double value) {
  auto p = m.effects.params(s.kind);
  p[s.i] = value;
  m.effects.set(s.kind, p);
}

// BOBYQA from each start (points in the unit cube of `slots`); leaves the best in obj.model.
double minimise_from(Objective& obj, const std::vector<Slot>& slots, const FitOptions& o,
                     const std::vector<std::vector<double>>& starts);

std::vector<double> units_now(const Objective& obj, const std::vector<Slot>& slots) {
  std::vector<double> x(slots.size());
  for (std::size_t i = 0; i < slots.size(); ++i) x[i] = slots[i].to_unit(obj.model.effects.params(slots[i].kind)[slots[i].i]);
  return x;
}

// BOBYQA over `slots` from where they stand and, for a new effect, from several starts; leaves
// the best in obj.model.
double fit_from_starts(Objective& obj, const std::vector<Slot>& slots, const FitOptions& o) {
  const std::size_t n = slots.size();
  const std::vector<double> now = units_now(obj, slots);
  std::vector<std::vector<double>> starts{now};
  // Parameters already fitted (the nominal ones, accepted effects) start where they are; a new
  // effect's parameters from its neutral value and from two points across their range.
  // Also with the fitted ones back at their neutral values: a re-fitted dead zone can have
  // absorbed part of, say, friction, and the joint fit must be able to give it back.
  for (bool reset : {false, true})
    for (double f : {0.3, 0.7}) {
      auto x = now;
      bool any = false;
      for (std::size_t i = 0; i < n; ++i) {
        if (slots[i].fresh) x[i] = f, any = true;
        else if (reset) x[i] = slots[i].to_unit(slots[i].spec.neutral);
      }
      if (any) starts.push_back(x);
    }
  // And everything at its neutral value: a re-fit gone astray (a gain pushed to where it absorbs
  // an unmodelled effect) must not be every start's starting point.
  std::vector<double> all_neutral(n);
  for (std::size_t i = 0; i < n; ++i) all_neutral[i] = slots[i].to_unit(slots[i].spec.neutral);
  if (all_neutral != now) starts.push_back(all_neutral);
  return minimise_from(obj, slots, o, starts);
}

// Minimises over the continuous slots by BOBYQA from a few starts (only from where they stand
// when `from_current_only`); leaves the best in obj.model.
// A new effect's parameter that is a member of its family of its own (starts_alone: a spool's
// speed limit, which does nothing while a lag beside it smooths the command) is fitted apart:
// the rest first with it neutral, then it alone with the rest of its effect neutral, with the
// fitted parameters where they stand and back at neutral; the better fit stays. Apart, each
// search has fewer dimensions, and costs less. Its own fit starts from a third of its range with
// the fitted parameters, and also from where a one-dimensional fit of it alone (those held)
// placed it: moved together from the start, the fitted parameters can walk back to where they had
// absorbed its effect (a gain of 0.3 for a slow spool) before it acts, and either start alone
// missed some spool speeds (tests/diag/effect_fit_test.cpp).
// Once its effect is fitted, such a member left at its neutral value stays out of later fits.
double local_fit(Objective& obj, const std::vector<Slot>& all_slots, const FitOptions& o, bool from_current_only = false) {
  std::vector<Slot> slots;
  for (const auto& s : all_slots)
    if (s.fresh || !s.spec.starts_alone || obj.model.effects.params(s.kind)[s.i] != s.spec.neutral) slots.push_back(s);
  if (slots.empty()) return obj.gap();
  if (from_current_only) return minimise_from(obj, slots, o, {units_now(obj, slots)});
  std::vector<Slot> rest, alone, fitted;
  for (const auto& s : slots) {
    (s.fresh && s.spec.starts_alone ? alone : rest).push_back(s);
    if (!s.fresh) fitted.push_back(s);
  }
  const ReplayModel before = obj.model;
  double best = rest.empty() ? obj.gap() : fit_from_starts(obj, rest, o);
  ReplayModel best_model = obj.model;
  for (const auto& a : alone) {
    obj.model = before;
    auto member = fitted;
    member.push_back(a);
    std::vector<std::vector<double>> starts;
    for (bool reset : {false, true}) {
      obj.model = before;
      for (std::size_t i = 0; reset && i < fitted.size(); ++i) put(obj.model, fitted[i], fitted[i].spec.neutral);
      auto x = units_now(obj, member);
      x.back() = 0.3;
      starts.push_back(x);
      minimise_from(obj, {a}, o, {{0.3}});
      starts.push_back(units_now(obj, member));
    }
    obj.model = before;
    if (const double g = minimise_from(obj, member, o, starts); g < best) best = g, best_model = obj.model;
  }
  obj.model = best_model;
  return best;
}

double minimise_from(Objective& obj, const std::vector<Slot>& slots, const FitOptions& o,
                     const std::vector<std::vector<double>>& starts) {
  const std::size_t n = slots.size();
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_x = starts.front();
  for (auto x : starts) {
    nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(n));
    opt.set_lower_bounds(std::vector<double>(n, 0.0));
    opt.set_upper_bounds(std::vector<double>(n, 1.0));
    opt.set_xtol_abs(1e-5);
    opt.set_ftol_rel(1e-7);
    opt.set_maxeval(static_cast<int>(o.max_evaluations_per_start));
    opt.set_initial_step(0.1);
    auto f = [](unsigned, const double* xs, double*, void* data) {
      auto* c = static_cast<std::pair<Objective*, const std::vector<Slot>*>*>(data);
      for (std::size_t i = 0; i < c->second->size(); ++i) put(c->first->model, (*c->second)[i], (*c->second)[i].from_unit(xs[i]));
      return c->first->gap();
    };
    std::pair<Objective*, const std::vector<Slot>*> ctx{&obj, &slots};
    opt.set_min_objective(f, &ctx);
    double value = std::numeric_limits<double>::infinity();
    try {
      opt.optimize(x, value);
    } catch (const std::exception&) {  // roundoff-limited or max-eval stops still leave x usable
      for (std::size_t i = 0; i < n; ++i) put(obj.model, slots[i], slots[i].from_unit(x[i]));
      value = obj.gap();
    }
    if (value < best) best = value, best_x = x;
  }
  for (std::size_t i = 0; i < n; ++i) put(obj.model, slots[i], slots[i].from_unit(best_x[i]));
  return best;
}

// A grid over one slot with the continuous slots fitted at each value would be costly; the grid
// slots (delay, sensor step) are fitted alone, the continuous ones afterwards at the best value.
double grid_fit(Objective& obj, const Slot& s, const std::vector<double>& values) {
  double best = std::numeric_limits<double>::infinity(), best_v = values.front();
  for (double v : values) {
    put(obj.model, s, v);
    if (const double g = obj.gap(); g < best) best = g, best_v = v;
  }
  put(obj.model, s, best_v);
  return best;
}

std::vector<double> quantization_grid(double lo, double hi, std::size_t n, bool with_zero) {
  std::vector<double> v;
  if (with_zero) v.push_back(0.0);
  for (std::size_t i = 0; i < n; ++i) v.push_back(lo * std::pow(hi / lo, static_cast<double>(i) / static_cast<double>(n - 1)));
  return v;
}

}  // namespace

EffectFit fit_effects(const ReplayModel& base, std::span<const EffectKind> kinds, std::span<const core::Run* const> runs,
                      const FitOptions& o) {
  Objective obj{base, runs, o.horizon};
  std::vector<Slot> continuous, grid, grid_after;
  for (auto kind : kinds) {
    const bool fresh = !obj.model.effects.on(kind);
    if (fresh) {
      plant::EffectParams p{};
      const auto specs = plant::param_specs(kind);
      for (std::size_t i = 0; i < specs.size(); ++i) p[i] = specs[i].neutral;
      obj.model.effects.set(kind, p);
    }
    const auto specs = plant::param_specs(kind);
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const Slot s{kind, i, specs[i], fresh};
      if (specs[i].fitted_last && !o.fit_last && obj.model.effects.params(kind)[i] == specs[i].neutral) continue;
      if (specs[i].grid_after_the_rest) {
        if (fresh) grid_after.push_back(s);  // an accepted effect keeps its shape
        continue;
      }
      (specs[i].integer || kind == EffectKind::kSensorQuantization ? grid : continuous).push_back(s);
    }
  }
  auto grid_then_local = [&](Objective& fit) {
    double gap = std::numeric_limits<double>::infinity();
    for (const auto& s : grid) {
      if (s.spec.integer) {
        std::vector<double> values;
        for (double v = s.spec.lo; v <= s.spec.hi; v += 1.0) values.push_back(v);
        gap = grid_fit(fit, s, values);
      } else {
        gap = grid_fit(fit, s, quantization_grid(0.02, s.spec.hi, 60, true));
        const double coarse = fit.model.effects.params(s.kind)[s.i];
        if (coarse > 0.0) gap = grid_fit(fit, s, quantization_grid(coarse / 1.12, std::min(s.spec.hi, coarse * 1.12), 15, false));
      }
    }
    if (!continuous.empty()) gap = local_fit(fit, continuous, o);
    // The grid chose its value with the continuous parameters where they stood (a fresh lag at
    // zero, whose share of the timing the grid then gives the delay); with them fitted, another
    // value can be better (a line of 2.5 samples' transport and a 10 ms lag: 3 samples alone, 2
    // with the lag beside them). From the grid's value the fit walks a sample at a time, each
    // way, re-fitting the continuous parameters at each from the last fit, while the gap falls.
    for (const auto& s : grid) {
      if (!s.spec.integer || continuous.empty()) continue;
      const ReplayModel at_grid = fit.model;
      ReplayModel best_model = fit.model;
      for (double direction : {-1.0, 1.0}) {
        ReplayModel from = at_grid;
        for (double v = at_grid.effects.params(s.kind)[s.i] + direction; v >= s.spec.lo && v <= s.spec.hi; v += direction) {
          fit.model = from;
          put(fit.model, s, v);
          const double g = local_fit(fit, continuous, o, true);
          if (g >= gap) break;
          gap = g, best_model = from = fit.model;
        }
      }
      fit.model = best_model;
    }
    // A shape parameter on its grid, the rest re-fitted at each value from where the first fit left
    // them: the gap can be far more sensitive to the shape than to the rest (a position gain's
    // averaging length: 0.04 mm at the right length, 3-24 mm one or more away, slopes alike).
    for (const auto& s : grid_after) {
      const ReplayModel start = fit.model;
      ReplayModel best_model = fit.model;
      double best = gap;
      for (double v = s.spec.lo; v <= s.spec.hi; v += 1.0) {
        fit.model = start;
        put(fit.model, s, v);
        if (const double g = local_fit(fit, continuous, o, true); g < best) best = g, best_model = fit.model;
      }
      fit.model = best_model, gap = best;
    }
    return std::isfinite(gap) ? gap : fit.gap();
  };
  double gap = grid_then_local(obj);
  // A grid value is chosen with the other parameters where they stand; when those were fitted
  // without it (a re-fitted gain pushed to its bound to absorb a delay), the grid also runs from
  // their neutral values, and the better fit stays.
  bool fitted_elsewhere = false;
  for (const auto& s : continuous)
    fitted_elsewhere = fitted_elsewhere || (!s.fresh && base.effects.params(s.kind)[s.i] != s.spec.neutral);
  if (!grid.empty() && fitted_elsewhere) {
    Objective from_neutral{obj.model, runs, o.horizon};
    for (const auto& s : continuous) put(from_neutral.model, s, s.spec.neutral);
    const double g = grid_then_local(from_neutral);
    obj.evaluations += from_neutral.evaluations;
    if (g < gap) gap = g, obj.model = from_neutral.model;
  }
  return {obj.model, gap, obj.evaluations};
}

EffectFit refit_nominal(const ReplayModel& base, std::span<const core::Run* const> runs, const FitOptions& o) {
  const EffectKind kinds[] = {EffectKind::kGainChange, EffectKind::kDeadzoneShift};
  return fit_effects(base, kinds, runs, o);
}

}  // namespace epa::diag
