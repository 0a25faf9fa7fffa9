#include "ident/arx_estimator.hpp"

#include <Eigen/Dense>
#include <algorithm>

#include "core/hammerstein_model.hpp"

namespace epa::ident {

std::size_t ArxOrders::first_row() const {
  return static_cast<std::size_t>(std::max(na, nk + nb - 1));
}

core::Status ArxOrders::validate() const {
  const int max_order = static_cast<int>(core::kMaxModelOrder);
  if (na < 0 || na > max_order)
    return core::invalid_argument("na = " + std::to_string(na) + ": must lie in [0, " + std::to_string(max_order) + "]");
  if (nb < 1) return core::invalid_argument("nb = " + std::to_string(nb) + ": must be >= 1");
  if (nk < 1)
    return core::invalid_argument("nk = " + std::to_string(nk) +
                                  ": must be >= 1 (y(k) is read before u(k) is applied, so it cannot depend on it)");
  if (nk + nb - 1 > max_order)
    return core::invalid_argument("nk + nb - 1 = " + std::to_string(nk + nb - 1) + ": B's order must be <= " +
                                  std::to_string(max_order));
  return core::ok();
}

std::string ArxOrders::to_string() const {
  return "na=" + std::to_string(na) + " nb=" + std::to_string(nb) + " nk=" + std::to_string(nk);
}

core::Polynomial ArxModel::A() const {
  std::vector<double> c{1.0};
  c.insert(c.end(), a.begin(), a.end());
  return core::Polynomial(std::move(c));
}

core::Polynomial ArxModel::B() const {
  std::vector<double> c(static_cast<std::size_t>(orders.nk), 0.0);
  c.insert(c.end(), b.begin(), b.end());
  return core::Polynomial(std::move(c));
}

// The least squares is Ljung's "square-root" form (System Identification, 2nd ed., pp. 318-319):
// a Householder QR of the augmented matrix [Phi Y], done in place, gives R = [R1 r; 0 rho], so
// theta solves R1 theta = r and the residual sum of squares is rho^2, with no pass over Phi or Y
// afterwards. R1 (d x d) then goes through a column-pivoted QR, which reveals the rank exactly as a
// pivoted QR of Phi would (Q is orthogonal: same singular values).
struct ArxRegression::Impl {
  ArxOrders orders;
  std::size_t first = 0;
  std::size_t rows = 0;
  const std::vector<Segment>* segments = nullptr;  // the caller's data (y, raw u)
  std::vector<std::vector<double>> u_through;      // dead_zone(u) per segment, once set
  mutable Eigen::MatrixXd aug;                     // [Phi Y], overwritten by every solve

  void fill() const {
    const auto na = static_cast<std::size_t>(orders.na), nb = static_cast<std::size_t>(orders.nb),
               nk = static_cast<std::size_t>(orders.nk);
    Eigen::Index r0 = 0;
    for (std::size_t s = 0; s < segments->size(); ++s) {
      const auto& y = (*segments)[s].y;
      const auto& u = u_through.empty() ? (*segments)[s].u : u_through[s];
      if (y.size() <= first) continue;
      const std::size_t n = y.size() - first;
      // Column by column: each is a shifted copy of y or u, so this streams through memory.
      for (std::size_t j = 0; j < na; ++j) {
        double* c = aug.col(static_cast<Eigen::Index>(j)).data() + r0;
        const double* src = y.data() + first - 1 - j;
        for (std::size_t i = 0; i < n; ++i) c[i] = -src[i];
      }
      for (std::size_t j = 0; j < nb; ++j) {
        double* c = aug.col(static_cast<Eigen::Index>(na + j)).data() + r0;
        const double* src = u.data() + first - nk - j;
        for (std::size_t i = 0; i < n; ++i) c[i] = src[i];
      }
      double* c = aug.col(static_cast<Eigen::Index>(na + nb)).data() + r0;
      for (std::size_t i = 0; i < n; ++i) c[i] = y[first + i];
      r0 += static_cast<Eigen::Index>(n);
    }
  }
};

ArxRegression::ArxRegression(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ArxRegression::ArxRegression(ArxRegression&&) noexcept = default;
ArxRegression& ArxRegression::operator=(ArxRegression&&) noexcept = default;
ArxRegression::~ArxRegression() = default;

std::size_t ArxRegression::rows() const { return impl_->rows; }
const ArxOrders& ArxRegression::orders() const { return impl_->orders; }

core::Result<ArxRegression> ArxRegression::make(const std::vector<Segment>& segments, const ArxOrders& orders,
                                                std::size_t first_row) {
  if (auto s = orders.validate(); !s) return s.error();
  auto impl = std::make_unique<Impl>();
  impl->orders = orders;
  impl->first = std::max(first_row, orders.first_row());
  impl->segments = &segments;
  for (const auto& s : segments)
    if (s.size() > impl->first) impl->rows += s.size() - impl->first;
  const auto d = static_cast<std::size_t>(orders.d());
  if (impl->rows <= d)
    return core::invalid_argument("ARX " + orders.to_string() + ": " + std::to_string(impl->rows) +
                                  " regression rows for " + std::to_string(d) +
                                  " parameters: give longer runs (at least several hundred samples)");
  impl->aug.resize(static_cast<Eigen::Index>(impl->rows), static_cast<Eigen::Index>(d + 1));
  return ArxRegression(std::move(impl));
}

void ArxRegression::set_input_through(const core::DeadZone& dz) {
  const auto& segments = *impl_->segments;
  impl_->u_through.resize(segments.size());
  for (std::size_t s = 0; s < segments.size(); ++s) {
    impl_->u_through[s].resize(segments[s].u.size());
    for (std::size_t k = 0; k < segments[s].u.size(); ++k) impl_->u_through[s][k] = dz.apply(segments[s].u[k]);
  }
}

core::Result<ArxEstimate> ArxRegression::solve(bool allow_rank_deficient) const {
  const ArxOrders& o = impl_->orders;
  const auto d = static_cast<Eigen::Index>(o.d());
  impl_->fill();
  Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(impl_->aug);  // in place: aug now holds R
  const Eigen::MatrixXd R1 = impl_->aug.topLeftCorner(d, d).triangularView<Eigen::Upper>();
  const Eigen::VectorXd r = impl_->aug.col(d).head(d);
  const double rho = impl_->aug(d, d);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> small(R1);
  ArxEstimate e;
  e.rank = static_cast<std::size_t>(small.rank());
  if (e.rank < static_cast<std::size_t>(o.d()) && !allow_rank_deficient)
    return core::numerical_error(
        "ARX " + o.to_string() + ": the regression matrix has rank " + std::to_string(e.rank) + " of " +
        std::to_string(o.d()) + ": the data do not excite the model (a valve command that is constant, never "
        "leaves the dead band, or a piston that never moves); record an excitation run (epa excite) or lower the orders");
  const Eigen::VectorXd theta = small.solve(r);
  e.N = rows();
  // rho^2 is the residual of the full-rank solution; a rank-deficient one adds what R1 leaves.
  const double sse = rho * rho + (e.rank < static_cast<std::size_t>(o.d()) ? (R1 * theta - r).squaredNorm() : 0.0);
  e.loss = sse / static_cast<double>(e.N);
  e.model.orders = o;
  e.model.a.assign(theta.data(), theta.data() + o.na);
  e.model.b.assign(theta.data() + o.na, theta.data() + o.d());
  return e;
}

core::Result<ArxEstimate> estimate_arx(const std::vector<Segment>& segments, const ArxOrders& orders,
                                       std::size_t first_row) {
  auto reg = ArxRegression::make(segments, orders, first_row);
  if (!reg) return reg.error();
  return reg->solve();
}

std::vector<Segment> through_dead_zone(const std::vector<Segment>& segments, const core::DeadZone& dz) {
  std::vector<Segment> out = segments;
  for (auto& s : out)
    for (double& u : s.u) u = dz.apply(u);
  return out;
}

}  // namespace epa::ident
