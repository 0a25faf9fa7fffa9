#pragma once
// ARX least squares, in the System Identification toolbox's conventions:
//
//   A(q) y(k) = B(q) u(k) + e(k)
//   A = 1 + a_1 q^-1 + ... + a_na q^-na
//   B = b_1 q^-nk + ... + b_nb q^-(nk+nb-1)      (nb coefficients, nk samples of delay)
//
// so the paper's eq 9 is na = 3, nb = 3, nk = 1, and core's B polynomial is {0, b_1, b_2, b_3}.
// Row k of the regression is  y(k) = [-y(k-1) ... -y(k-na), u(k-nk) ... u(k-nk-nb+1)] theta  for
// k >= first_row = max(na, nk + nb - 1) inside each segment, so no regressor crosses a segment (run)
// boundary. theta = [a_1..a_na, b_1..b_nb] is solved by a Householder QR of the regression matrix
// (never the normal equations, which square its condition number): see arx_estimator.cpp.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/dead_zone.hpp"
#include "core/polynomial.hpp"
#include "core/result.hpp"
#include "ident/ident_data.hpp"

namespace epa::ident {

struct ArxOrders {
  int na = 3;  // poles (A's order)
  int nb = 3;  // B coefficients
  int nk = 1;  // input delay, samples (>= 1: y(k) cannot depend on u(k), core/run.hpp)

  int d() const { return na + nb; }  // number of estimated parameters
  std::size_t first_row() const;     // max(na, nk + nb - 1)
  core::Status validate() const;     // na >= 0, nb >= 1, nk >= 1, A and B within core::kMaxModelOrder
  std::string to_string() const;     // "na=3 nb=3 nk=1"
  bool operator==(const ArxOrders&) const = default;
};

struct ArxModel {
  ArxOrders orders;
  std::vector<double> a;  // a_1 .. a_na
  std::vector<double> b;  // b_1 .. b_nb (coefficients of q^-nk .. q^-(nk+nb-1))

  core::Polynomial A() const;  // {1, a_1, ..., a_na}
  core::Polynomial B() const;  // {0 (nk times), b_1, ..., b_nb}
};

struct ArxEstimate {
  ArxModel model;
  std::size_t N = 0;     // regression rows used
  double loss = 0.0;     // V = (1/N) sum e(k)^2, e the one-step residual
  std::size_t rank = 0;  // numerical rank of the regression matrix
};

// The regression of a set of segments for one order, kept (data and work matrix) so the dead-zone
// fit can solve it again for each candidate dead zone without allocating.
class ArxRegression {
 public:
  // first_row: first sample of each segment used as a target (0: orders.first_row(); a larger
  // value makes candidates of different orders score the same samples). Errors: invalid orders,
  // fewer rows than parameters. `segments` is referenced, not copied: it must outlive the result.
  static core::Result<ArxRegression> make(const std::vector<Segment>& segments, const ArxOrders& orders,
                                          std::size_t first_row = 0);
  ArxRegression(ArxRegression&&) noexcept;
  ArxRegression& operator=(ArxRegression&&) noexcept;
  ~ArxRegression();

  // Uses dead_zone.apply(u) as the input from now on (u: the segments given to make()).
  void set_input_through(const core::DeadZone& dead_zone);

  // Least squares. A rank-deficient matrix is an error naming what is not excited, unless
  // allow_rank_deficient (the dead-zone search meets such candidates and only needs their loss).
  core::Result<ArxEstimate> solve(bool allow_rank_deficient = false) const;

  std::size_t rows() const;
  const ArxOrders& orders() const;

 private:
  struct Impl;
  explicit ArxRegression(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// make() + solve() in one call.
core::Result<ArxEstimate> estimate_arx(const std::vector<Segment>& segments, const ArxOrders& orders,
                                       std::size_t first_row = 0);

// Segments with u replaced by dead_zone.apply(u): the input of the linear part.
std::vector<Segment> through_dead_zone(const std::vector<Segment>& segments, const core::DeadZone& dead_zone);

}  // namespace epa::ident
