#include "ident/arx_metrics.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace epa::ident {

namespace {

constexpr double kSimulationDivergedV = 1e12;  // a simulation beyond this has diverged

// sum_i a_i yhat(k-i) + sum_j b_j u(k-nk-j): the right-hand side of y(k) = -A' y + B u.
template <typename Past>
double arx_output(const ArxModel& m, const Segment& s, std::size_t k, Past past) {
  double y = 0.0;
  for (int i = 0; i < m.orders.na; ++i) y -= m.a[static_cast<std::size_t>(i)] * past(k - 1 - static_cast<std::size_t>(i));
  for (int j = 0; j < m.orders.nb; ++j)
    y += m.b[static_cast<std::size_t>(j)] * s.u[k - static_cast<std::size_t>(m.orders.nk + j)];
  return y;
}

}  // namespace

std::vector<double> predict_one_step(const ArxModel& m, const Segment& s, std::size_t first) {
  first = std::max(first, m.orders.first_row());
  std::vector<double> yhat = s.y;
  for (std::size_t k = first; k < s.size(); ++k) yhat[k] = arx_output(m, s, k, [&](std::size_t i) { return s.y[i]; });
  return yhat;
}

std::vector<double> initial_past(const ArxModel& m, const Segment& s, std::size_t first) {
  const auto na = static_cast<std::size_t>(m.orders.na);
  std::vector<double> past(na);
  for (std::size_t i = 0; i < na; ++i) past[i] = s.y[first - 1 - i];
  if (na == 0 || s.size() < first + kInitialStateSamples) return past;  // too short to average over: as measured
  const auto samples = static_cast<Eigen::Index>(kInitialStateSamples);
  // The free run over those samples is affine in the past: its answer to the input from a past of
  // zeros, plus one column per past value (the run from that value 1 and the rest 0, less that answer).
  auto run = [&](std::size_t unit) {  // unit == na: from a past of zeros
    Eigen::VectorXd y(samples);
    auto before = [&](std::size_t i) { return i >= first ? y(static_cast<Eigen::Index>(i - first)) : first - 1 - i == unit ? 1.0 : 0.0; };
    for (Eigen::Index j = 0; j < samples; ++j) y(j) = arx_output(m, s, first + static_cast<std::size_t>(j), before);
    return y;
  };
  const Eigen::VectorXd input_answer = run(na);
  Eigen::MatrixXd columns(samples, static_cast<Eigen::Index>(na));
  for (std::size_t i = 0; i < na; ++i) columns.col(static_cast<Eigen::Index>(i)) = run(i) - input_answer;
  const Eigen::VectorXd measured = Eigen::Map<const Eigen::VectorXd>(s.y.data() + first, samples);
  if (!columns.allFinite() || !input_answer.allFinite()) return past;  // a diverging model: as measured
  const Eigen::VectorXd estimate = columns.colPivHouseholderQr().solve(measured - input_answer);
  if (!estimate.allFinite()) return past;
  for (std::size_t i = 0; i < na; ++i) past[i] = estimate(static_cast<Eigen::Index>(i));
  return past;
}

std::vector<double> simulate_free_run(const ArxModel& m, const Segment& s, std::size_t first) {
  first = std::max(first, m.orders.first_row());
  std::vector<double> yhat = s.y;
  if (first >= s.size()) return yhat;
  const std::vector<double> past = initial_past(m, s, first);
  auto before = [&](std::size_t i) { return i >= first ? yhat[i] : past[first - 1 - i]; };  // arx_output reaches back na
  for (std::size_t k = first; k < s.size(); ++k) {
    const double y = arx_output(m, s, k, before);
    if (!(std::abs(y) <= kSimulationDivergedV)) {
      std::fill(yhat.begin() + static_cast<std::ptrdiff_t>(k), yhat.end(), std::copysign(kSimulationDivergedV, y));
      break;
    }
    yhat[k] = y;
  }
  return yhat;
}

double nrmse_fit_percent(const std::vector<Segment>& segments, const std::vector<std::vector<double>>& yhat,
                         std::size_t first) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& s : segments)
    for (std::size_t k = first; k < s.size(); ++k) sum += s.y[k], ++n;
  if (n == 0) return 0.0;
  const double mean = sum / static_cast<double>(n);
  double err = 0.0, spread = 0.0;
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const auto& s = segments[i];
    for (std::size_t k = first; k < s.size(); ++k) {
      err += (s.y[k] - yhat[i][k]) * (s.y[k] - yhat[i][k]);
      spread += (s.y[k] - mean) * (s.y[k] - mean);
    }
  }
  if (!(spread > 0.0)) return err > 0.0 ? -INFINITY : 100.0;
  return 100.0 * (1.0 - std::sqrt(err / spread));
}

Fit fit_percent(const ArxModel& m, const std::vector<Segment>& segments, std::size_t first) {
  first = std::max(first, m.orders.first_row());
  std::vector<std::vector<double>> one_step, sim;
  for (const auto& s : segments) {
    one_step.push_back(predict_one_step(m, s, first));
    sim.push_back(simulate_free_run(m, s, first));
  }
  return {nrmse_fit_percent(segments, one_step, first), nrmse_fit_percent(segments, sim, first)};
}

InformationCriteria information_criteria(double loss, std::size_t N, int d) {
  const double n = static_cast<double>(N), p = static_cast<double>(d);
  InformationCriteria ic;
  ic.loss = loss;
  ic.fpe = p < n ? loss * (1.0 + p / n) / (1.0 - p / n) : INFINITY;
  ic.aic = n * std::log(std::max(loss, 1e-300)) + 2.0 * p;
  return ic;
}

}  // namespace epa::ident
