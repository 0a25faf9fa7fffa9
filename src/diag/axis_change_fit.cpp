#include "diag/axis_change_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlopt.hpp>

namespace epa::diag {

namespace {

constexpr unsigned kEvaluationsPerDimension = 120;
constexpr double kInitialStep = 0.15;  // of the unit box
constexpr int kScanPoints = 12;         // a jagged parameter's coarse scan over its range, before the local search

double to_unit(const ChangeParam& p, double v) {
  v = std::clamp(v, p.lo, p.hi);
  return p.log_scale ? std::log(v / p.lo) / std::log(p.hi / p.lo) : (v - p.lo) / (p.hi - p.lo);
}

double from_unit(const ChangeParam& p, double x) {
  x = std::clamp(x, 0.0, 1.0);
  return p.log_scale ? p.lo * std::pow(p.hi / p.lo, x) : p.lo + x * (p.hi - p.lo);
}

struct Problem {
  const ChangeFitData* data;
  AxisChange change;                              // the terms, their values written by put()
  std::vector<std::pair<std::size_t, ChangeParam>> slots;  // (term index, parameter) per dimension
  std::size_t evaluations = 0;

  void put(const double* x) {
    std::size_t d = 0;
    for (auto& v : change.values) v.clear();
    for (const auto& [i, p] : slots) change.values[i].push_back(from_unit(p, x[d++]));
  }
  double train_gap() {
    ++evaluations;
    return from_rest_gap_mm(apply_change(data->commissioned, change), data->Ts, data->train, data->scope);
  }
};

// Where a one-term fit of a jagged parameter (ChangeParam::jagged: friction, supply) starts its local
// search: the best of x0 and a coarse scan over the unit range. Searched from the neutral point
// alone, a window whose friction had doubled fitted it as x0.9. Only such parameters: scanned, the
// spool lag found far basins at the range's end on 15 s parts of an unchanged axis's runs (100 ms
// against 12), which would have widened its tolerance eight-fold.
void start_from_best_of_scan(Problem& problem, std::vector<double>& x) {
  problem.put(x.data());
  double best = problem.train_gap();
  for (int i = 0; i < kScanPoints; ++i) {
    const double xi = (i + 0.5) / kScanPoints;
    problem.put(&xi);
    if (const double gap = problem.train_gap(); gap < best) best = gap, x[0] = xi;
  }
}

// Minimises the training gap over the continuous values from x (unit box); returns the gap.
double minimise(Problem& problem, std::vector<double>& x) {
  const std::size_t n = x.size();
  if (n == 0) return problem.train_gap();
  if (problem.change.terms.size() == 1 && n == 1 && problem.slots.front().second.jagged) start_from_best_of_scan(problem, x);
  nlopt::opt opt(nlopt::LN_SBPLX, static_cast<unsigned>(n));
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  opt.set_upper_bounds(std::vector<double>(n, 1.0));
  opt.set_xtol_abs(1e-4);
  opt.set_ftol_rel(1e-6);
  opt.set_maxeval(static_cast<int>(kEvaluationsPerDimension * n));
  opt.set_initial_step(kInitialStep);
  auto f = [](unsigned, const double* xs, double*, void* data) {
    auto* p = static_cast<Problem*>(data);
    p->put(xs);
    return p->train_gap();
  };
  opt.set_min_objective(f, &problem);
  double best = std::numeric_limits<double>::infinity();
  try {
    opt.optimize(x, best);
  } catch (const std::exception&) {  // a round-off stop keeps the best point NLopt reports in x
    best = std::numeric_limits<double>::infinity();
  }
  problem.put(x.data());
  return std::isfinite(best) ? best : problem.train_gap();
}

}  // namespace

ChangeFit fit_change(const ChangeFitData& data, const std::vector<ChangeTerm>& terms, const AxisChange& start) {
  Problem problem{&data, {}, {}, 0};
  problem.change.terms = terms;
  problem.change.values.resize(terms.size());
  std::vector<double> x0;
  for (std::size_t i = 0; i < terms.size(); ++i) {
    const auto params = change_params(terms[i], data.commissioned);
    const auto* given = start.values_of(terms[i]);
    for (std::size_t j = 0; j < params.size(); ++j) {
      problem.slots.emplace_back(i, params[j]);
      x0.push_back(to_unit(params[j], given && j < given->size() ? (*given)[j] : params[j].neutral));
    }
  }
  const bool delay = std::find(terms.begin(), terms.end(), ChangeTerm::kDeadTime) != terms.end();
  ChangeFit best;
  best.train_gap_mm = std::numeric_limits<double>::infinity();
  const int lo = delay ? 0 : data.commissioned.delay_samples, hi = delay ? core::StickSlipParams::kMaxDelay : lo;
  for (int d = lo; d <= hi; ++d) {
    problem.change.delay_samples = d;
    std::vector<double> x = x0;
    const double gap = minimise(problem, x);
    if (gap < best.train_gap_mm) best.change = problem.change, best.train_gap_mm = gap;
  }
  best.evaluations = problem.evaluations;
  best.heldout_gap_mm = from_rest_gap_mm(apply_change(data.commissioned, best.change), data.Ts, data.heldout, data.scope);
  return best;
}

}  // namespace epa::diag
