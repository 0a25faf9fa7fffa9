#include "ident/output_error_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/format.hpp"
#include "core/polynomial.hpp"

namespace epa::ident {

namespace {

using core::format_number;

constexpr double kFitDivergedV = 1e6;        // |yhat| beyond this: the simulation has diverged
constexpr double kLambdaStart = 1e-3;        // Marquardt damping, relative to diag(J'J)
constexpr double kLambdaMax = 1e12;          // damping this large: no step helps any more
constexpr double kRelativeDecrease = 1e-9;   // an accepted step gaining less than this ends the fit
constexpr double kMinCurvature = 1e-300;     // floor of diag(J'J), so an unexcited parameter stays put
constexpr std::size_t kDeadZoneParameters = 3;  // ln(m_r / m_l), b_r, b_l
constexpr double kShrinkMargin = 0.999;      // a start beyond the pole radius is pulled just inside it

// Where each parameter sits in the vector the optimiser moves:
//   [A part | b_1..b_nb | ln(m_r/m_l), b_r, b_l]
// The A part is c_1..c_{na-1} of A = (1 - q)(1 + c_1 q + ...) when integrating, else a_1..a_na.
struct Layout {
  ArxOrders orders;
  bool integrating = true;

  std::size_t a_count() const { return static_cast<std::size_t>(integrating ? orders.na - 1 : orders.na); }
  std::size_t b_first() const { return a_count(); }
  std::size_t ratio() const { return a_count() + static_cast<std::size_t>(orders.nb); }
  std::size_t b_r() const { return ratio() + 1; }
  std::size_t b_l() const { return ratio() + 2; }
  std::size_t size() const { return ratio() + kDeadZoneParameters; }
};

struct Model {
  std::vector<double> a, b;  // a_1..a_na, b_1..b_nb
  core::DeadZone dead_zone;  // m_l = 1
};

Model unpack(const Layout& l, const Eigen::VectorXd& x) {
  const auto na = static_cast<std::size_t>(l.orders.na), nb = static_cast<std::size_t>(l.orders.nb);
  Model m;
  m.a.resize(na);
  if (l.integrating) {
    // a_i = c_i - c_{i-1} with c_0 = 1 and c_na = 0.
    for (std::size_t i = 1; i <= na; ++i) {
      const double c_i = i < na ? x[static_cast<Eigen::Index>(i - 1)] : 0.0;
      const double c_prev = i == 1 ? 1.0 : x[static_cast<Eigen::Index>(i - 2)];
      m.a[i - 1] = c_i - c_prev;
    }
  } else {
    for (std::size_t i = 0; i < na; ++i) m.a[i] = x[static_cast<Eigen::Index>(i)];
  }
  m.b.resize(nb);
  for (std::size_t j = 0; j < nb; ++j) m.b[j] = x[static_cast<Eigen::Index>(l.b_first() + j)];
  m.dead_zone = {.m_r = std::exp(x[static_cast<Eigen::Index>(l.ratio())]), .m_l = 1.0,
                 .b_r = x[static_cast<Eigen::Index>(l.b_r())], .b_l = x[static_cast<Eigen::Index>(l.b_l())]};
  return m;
}

// The start point in the optimiser's coordinates. An integrating layout divides A by (1 - q) and
// drops the remainder A(1), which is what moves the start's pole onto z = 1.
Eigen::VectorXd pack(const Layout& l, const ArxModel& model, const core::DeadZone& dz) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(l.size()));
  const auto na = static_cast<std::size_t>(l.orders.na);
  if (l.integrating) {
    double c = 1.0;
    for (std::size_t i = 1; i < na; ++i) {
      c = model.a[i - 1] + c;  // c_i = a_i + c_{i-1}
      x[static_cast<Eigen::Index>(i - 1)] = c;
    }
  } else {
    for (std::size_t i = 0; i < na; ++i) x[static_cast<Eigen::Index>(i)] = model.a[i];
  }
  // The products m B are what the data fix: move the start's m_l into B.
  for (std::size_t j = 0; j < model.b.size(); ++j) x[static_cast<Eigen::Index>(l.b_first() + j)] = model.b[j] * dz.m_l;
  x[static_cast<Eigen::Index>(l.ratio())] = std::log(dz.m_r / dz.m_l);
  x[static_cast<Eigen::Index>(l.b_r())] = dz.b_r;
  x[static_cast<Eigen::Index>(l.b_l())] = dz.b_l;
  return x;
}

constexpr std::size_t kStateHalfWidth = 8;  // samples each side of a window start for its initial state

struct Line {
  double centre = 0.0, level = 0.0, slope = 0.0;
  double at(std::size_t j) const { return level + slope * (static_cast<double>(j) - centre); }
};

// Least-squares line through y[k0 - h, k0 + h) (clipped to the data).
Line fit_line(const std::vector<double>& y, std::size_t k0, std::size_t h) {
  const std::size_t lo = k0 > h ? k0 - h : 0, hi = std::min(y.size(), k0 + h);
  Line l;
  double n = 0.0, sum = 0.0;
  for (std::size_t j = lo; j < hi; ++j) n += 1.0, sum += static_cast<double>(j);
  l.centre = sum / n;
  double sy = 0.0, sxy = 0.0, sxx = 0.0;
  for (std::size_t j = lo; j < hi; ++j) {
    const double x = static_cast<double>(j) - l.centre;
    sy += y[j], sxy += x * y[j], sxx += x * x;
  }
  l.level = sy / n;
  l.slope = sxx > 0.0 ? sxy / sxx : 0.0;
  return l;
}

// The windowed simulation and its sensitivities. Buffers are kept between evaluations.
class Simulation {
 public:
  Simulation(const std::vector<Segment>& segments, const Layout& layout, std::size_t window)
      : segments_(segments), layout_(layout), window_(window) {}

  std::size_t samples() const { return samples_; }
  std::size_t evaluations() const { return evaluations_; }

  // Sum of squared simulation errors; with J'J and J'r (J: d yhat / d x) when both are given.
  // Infinite when the simulation diverges.
  double evaluate(const Model& m, Eigen::MatrixXd* JtJ, Eigen::VectorXd* Jtr) {
    const bool jacobian = JtJ != nullptr && Jtr != nullptr;
    const std::size_t p = layout_.size();
    if (jacobian) {
      JtJ->setZero(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p));
      Jtr->setZero(static_cast<Eigen::Index>(p));
    }
    double sse = 0.0;
    samples_ = 0;
    ++evaluations_;
    for (const auto& s : segments_) {
      const double segment_sse = simulate_segment(s, m, jacobian ? JtJ : nullptr, jacobian ? Jtr : nullptr);
      if (!std::isfinite(segment_sse)) return INFINITY;
      sse += segment_sse;
    }
    return sse;
  }

 private:
  double simulate_segment(const Segment& s, const Model& m, Eigen::MatrixXd* JtJ, Eigen::VectorXd* Jtr) {
    const auto& o = layout_.orders;
    const auto na = static_cast<std::size_t>(o.na), nb = static_cast<std::size_t>(o.nb),
               nk = static_cast<std::size_t>(o.nk);
    const std::size_t first = o.first_row(), n = s.size();
    if (n <= first) return 0.0;
    const std::size_t p = layout_.size();
    const bool jacobian = JtJ != nullptr;
    const auto& dz = m.dead_zone;
    ud_.resize(n);
    for (std::size_t k = 0; k < n; ++k) ud_[k] = dz.apply(s.u[k]);
    if (jacobian) {
      d_ud_.assign(n * kDeadZoneParameters, 0.0);  // d u_d / d (ln m_r, b_r, b_l)
      for (std::size_t k = 0; k < n; ++k) {
        double* d = &d_ud_[k * kDeadZoneParameters];
        if (s.u[k] > dz.b_r) d[0] = dz.m_r * (s.u[k] - dz.b_r), d[1] = -dz.m_r;
        else if (s.u[k] < dz.b_l) d[2] = -dz.m_l;
      }
      sens_.assign(n * p, 0.0);
      g_.resize(static_cast<Eigen::Index>(p));
    }
    yhat_.assign(s.y.begin(), s.y.end());
    const std::size_t window = window_ == 0 ? n : window_;
    double sse = 0.0;
    for (std::size_t k0 = first; k0 < n;) {
      // A last window shorter than half a window joins the one before it.
      std::size_t k1 = std::min(n, k0 + window);
      if (n - k1 < window / 2) k1 = n;
      // A segment's initial state: the measured y before it smoothed by a straight line through
      // the samples around its start (position and velocity), so sensor noise does not start the
      // model with a spurious velocity that an integrating model carries as an offset ever after.
      // Later windows start from the measured samples (a line cannot follow a pulse's start).
      const Line line = k0 == first ? fit_line(s.y, k0, kStateHalfWidth) : Line{};
      auto past = [&](std::size_t j) { return j >= k0 ? yhat_[j] : k0 == first ? line.at(j) : s.y[j]; };
      for (std::size_t k = k0; k < k1; ++k) {
        double y = 0.0;
        for (std::size_t i = 1; i <= na; ++i) y -= m.a[i - 1] * past(k - i);
        for (std::size_t j = 0; j < nb; ++j) y += m.b[j] * ud_[k - nk - j];
        if (!(std::abs(y) <= kFitDivergedV)) return INFINITY;
        yhat_[k] = y;
        const double r = y - s.y[k];
        sse += r * r;
        ++samples_;
        if (!jacobian) continue;
        // Forcing terms: the explicit derivative of this step's right-hand side.
        double* g = &sens_[k * p];
        if (layout_.integrating) {
          for (std::size_t l = 1; l < na; ++l) g[l - 1] = -(past(k - l) - past(k - l - 1));
        } else {
          for (std::size_t i = 1; i <= na; ++i) g[i - 1] = -past(k - i);
        }
        for (std::size_t j = 0; j < nb; ++j) g[layout_.b_first() + j] = ud_[k - nk - j];
        for (std::size_t q = 0; q < kDeadZoneParameters; ++q) {
          double f = 0.0;
          for (std::size_t j = 0; j < nb; ++j) f += m.b[j] * d_ud_[(k - nk - j) * kDeadZoneParameters + q];
          g[layout_.ratio() + q] = f;
        }
        // ... plus the model's own past outputs, which depend on the parameters inside a window.
        for (std::size_t i = 1; i <= na && k - i >= k0; ++i) {
          const double a = m.a[i - 1];
          const double* prev = &sens_[(k - i) * p];
          for (std::size_t q = 0; q < p; ++q) g[q] -= a * prev[q];
        }
        for (std::size_t q = 0; q < p; ++q) g_[static_cast<Eigen::Index>(q)] = g[q];
        JtJ->selfadjointView<Eigen::Lower>().rankUpdate(g_);
        *Jtr += r * g_;
      }
      k0 = k1;
    }
    return sse;
  }

  const std::vector<Segment>& segments_;
  Layout layout_;
  std::size_t window_ = 0;
  std::size_t samples_ = 0, evaluations_ = 0;
  std::vector<double> ud_, d_ud_, yhat_, sens_;
  Eigen::VectorXd g_;
};

// The largest |pole| of the model apart from the integrator: the roots of C (integrating) or A.
double pole_radius(const Layout& l, const Eigen::VectorXd& x) {
  std::vector<double> c{1.0};
  for (std::size_t i = 0; i < l.a_count(); ++i) c.push_back(x[static_cast<Eigen::Index>(i)]);
  return core::Polynomial(std::move(c)).max_root_abs();
}

// Scales the A part so that its roots shrink by `factor` (c_i -> c_i factor^i).
void shrink_poles(const Layout& l, Eigen::VectorXd& x, double factor) {
  double f = 1.0;
  for (std::size_t i = 0; i < l.a_count(); ++i) x[static_cast<Eigen::Index>(i)] *= (f *= factor);
}

struct Bounds {
  Eigen::VectorXd lo, hi;
};

Bounds bounds(const Layout& l, const OutputErrorOptions& o) {
  const auto p = static_cast<Eigen::Index>(l.size());
  Bounds b{Eigen::VectorXd::Constant(p, -INFINITY), Eigen::VectorXd::Constant(p, INFINITY)};
  const auto ratio = static_cast<Eigen::Index>(l.ratio()), br = static_cast<Eigen::Index>(l.b_r()),
             bl = static_cast<Eigen::Index>(l.b_l());
  b.lo[ratio] = std::log(o.ratio_min), b.hi[ratio] = std::log(o.ratio_max);
  b.lo[br] = std::max(0.0, o.right.lo_v), b.hi[br] = o.right.hi_v;
  b.lo[bl] = o.left.lo_v, b.hi[bl] = std::min(0.0, o.left.hi_v);
  return b;
}

}  // namespace

core::Status OutputErrorOptions::validate() const {
  if (!(Ts > 0.0 && std::isfinite(Ts))) return core::invalid_argument("output-error fit: Ts must be > 0 s, got " + format_number(Ts));
  if (!(window_s >= 0.0 && std::isfinite(window_s)))
    return core::invalid_argument("output-error fit: the window must be >= 0 s, got " + format_number(window_s));
  if (!(slowest_mode_s >= 0.0 && std::isfinite(slowest_mode_s)))
    return core::invalid_argument("output-error fit: the slowest mode must be >= 0 s, got " + format_number(slowest_mode_s));
  if (!(ratio_min > 0.0 && ratio_min < ratio_max && std::isfinite(ratio_max)))
    return core::invalid_argument("output-error fit: the m_r/m_l range must satisfy 0 < min < max");
  if (!(right.lo_v <= right.hi_v && right.hi_v >= 0.0))
    return core::invalid_argument("output-error fit: the range of b_r [" + format_number(right.lo_v) + ", " +
                                  format_number(right.hi_v) + "] V is empty or below 0");
  if (!(left.lo_v <= left.hi_v && left.lo_v <= 0.0))
    return core::invalid_argument("output-error fit: the range of b_l [" + format_number(left.lo_v) + ", " +
                                  format_number(left.hi_v) + "] V is empty or above 0");
  return core::ok();
}

double windowed_simulation_loss(const std::vector<Segment>& segments, const ArxModel& model, const core::DeadZone& dz,
                                std::size_t window_samples) {
  const Layout layout{model.orders, false};
  Simulation sim(segments, layout, window_samples);
  const Model m{model.a, model.b, dz};
  const double sse = sim.evaluate(m, nullptr, nullptr);
  return sim.samples() > 0 ? sse / static_cast<double>(sim.samples()) : INFINITY;
}

core::Result<OutputErrorFit> fit_output_error(const std::vector<Segment>& segments, const ArxModel& start,
                                              const core::DeadZone& start_dz, const OutputErrorOptions& o) {
  if (auto s = o.validate(); !s) return s.error();
  if (auto s = start.orders.validate(); !s) return s.error();
  if (o.integrating && start.orders.na < 1)
    return core::invalid_argument("output-error fit: an integrating model needs na >= 1, got " + start.orders.to_string());
  if (auto s = start_dz.validate(); !s) return core::invalid_argument("output-error fit: start dead zone: " + s.error().message);
  const Layout layout{start.orders, o.integrating};
  const auto window = static_cast<std::size_t>(std::llround(o.window_s / o.Ts));
  if (o.window_s > 0.0 && window <= start.orders.first_row())
    return core::invalid_argument("output-error fit: a window of " + format_number(o.window_s) + " s is too short for " +
                                  start.orders.to_string());
  const Bounds box = bounds(layout, o);
  auto clamp = [&](Eigen::VectorXd x) { return Eigen::VectorXd(x.cwiseMax(box.lo).cwiseMin(box.hi)); };

  // Poles slower than the slowest mode allowed: none, or within the radius.
  const double max_radius = o.slowest_mode_s > 0.0 ? std::exp(-o.Ts / o.slowest_mode_s) : INFINITY;
  auto allowed = [&](const Eigen::VectorXd& x) { return pole_radius(layout, x) <= max_radius; };

  Simulation sim(segments, layout, window);
  Eigen::VectorXd x = clamp(pack(layout, start, start_dz));
  if (const double r = pole_radius(layout, x); r > max_radius) shrink_poles(layout, x, kShrinkMargin * max_radius / r);
  Eigen::MatrixXd JtJ;
  Eigen::VectorXd Jtr;
  double sse = sim.evaluate(unpack(layout, x), &JtJ, &Jtr);
  if (!std::isfinite(sse))
    return core::numerical_error("output-error fit: the start model's simulation diverges (" + start.orders.to_string() +
                                 "): its A has a root well outside the unit circle");
  if (sim.samples() == 0) return core::invalid_argument("output-error fit: no samples to simulate (segments too short)");
  OutputErrorFit fit;
  fit.samples = sim.samples();
  fit.start_loss = sse / static_cast<double>(fit.samples);
  fit.iterations = 1;

  double lambda = kLambdaStart;
  for (unsigned it = 1; it < o.max_iterations; ++it) {
    // J'J is filled in its lower triangle only.
    const Eigen::MatrixXd H = JtJ.selfadjointView<Eigen::Lower>();
    const Eigen::VectorXd scale = H.diagonal().cwiseMax(kMinCurvature);
    bool accepted = false;
    double new_sse = sse;
    Eigen::VectorXd x_new;
    // Parameters held at a bound by the gradient stay out of the step (an active set), so the
    // clamp below never bends the step of the free ones.
    std::vector<Eigen::Index> free;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const bool pushed_down = x[i] <= box.lo[i] && Jtr[i] > 0.0, pushed_up = x[i] >= box.hi[i] && Jtr[i] < 0.0;
      if (!pushed_down && !pushed_up) free.push_back(i);
    }
    if (free.empty()) break;
    const Eigen::MatrixXd H_free = H(free, free);
    const Eigen::VectorXd g_free = Jtr(free), scale_free = scale(free);
    while (lambda <= kLambdaMax) {
      Eigen::MatrixXd damped = H_free;
      damped.diagonal() += lambda * scale_free;
      const Eigen::VectorXd step = damped.ldlt().solve(-g_free);
      x_new = x;
      for (std::size_t i = 0; i < free.size(); ++i) x_new[free[i]] += step[static_cast<Eigen::Index>(i)];
      x_new = clamp(x_new);
      new_sse = allowed(x_new) ? sim.evaluate(unpack(layout, x_new), nullptr, nullptr) : INFINITY;
      if (new_sse < sse) {
        accepted = true;
        lambda = std::max(lambda / 3.0, 1e-12);
        break;
      }
      lambda *= 4.0;
    }
    if (!accepted) break;
    const bool small_gain = sse - new_sse < kRelativeDecrease * sse;
    x = x_new;
    sse = sim.evaluate(unpack(layout, x), &JtJ, &Jtr);
    ++fit.iterations;
    if (small_gain) break;
  }

  const Model m = unpack(layout, x);
  fit.model.orders = start.orders;
  fit.model.a = m.a;
  fit.model.b = m.b;
  fit.dead_zone = m.dead_zone;
  fit.loss = sse / static_cast<double>(fit.samples);
  fit.evaluations = sim.evaluations();
  return fit;
}

}  // namespace epa::ident
