#include "core/polynomial.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace epa::core {

int Polynomial::degree() const {
  for (int i = static_cast<int>(c_.size()) - 1; i >= 0; --i) {
    if (c_[static_cast<std::size_t>(i)] != 0.0) return i;
  }
  return -1;
}

Polynomial Polynomial::operator+(const Polynomial& other) const {
  std::vector<double> r(std::max(c_.size(), other.c_.size()), 0.0);
  for (std::size_t i = 0; i < r.size(); ++i) r[i] = (*this)[i] + other[i];
  return Polynomial(std::move(r));
}

Polynomial Polynomial::operator-(const Polynomial& other) const { return *this + other * -1.0; }

Polynomial Polynomial::operator*(const Polynomial& other) const {
  if (c_.empty() || other.c_.empty()) return {};
  std::vector<double> r(c_.size() + other.c_.size() - 1, 0.0);
  for (std::size_t i = 0; i < c_.size(); ++i)
    for (std::size_t j = 0; j < other.c_.size(); ++j) r[i + j] += c_[i] * other.c_[j];
  return Polynomial(std::move(r));
}

Polynomial Polynomial::operator*(double factor) const {
  std::vector<double> r = c_;
  for (double& v : r) v *= factor;
  return Polynomial(std::move(r));
}

double Polynomial::at(double q) const {
  double v = 0.0;  // Horner from the highest power
  for (auto it = c_.rbegin(); it != c_.rend(); ++it) v = v * q + *it;
  return v;
}

std::complex<double> Polynomial::at(std::complex<double> q) const {
  std::complex<double> v = 0.0;
  for (auto it = c_.rbegin(); it != c_.rend(); ++it) v = v * q + *it;
  return v;
}

std::vector<double> Polynomial::descending_z(std::size_t z_degree) const {
  std::vector<double> r(z_degree + 1, 0.0);
  for (std::size_t i = 0; i <= z_degree; ++i) r[i] = (*this)[i];
  return r;
}

std::vector<std::complex<double>> Polynomial::z_roots() const {
  if (c_.empty()) return {};
  return roots_descending(c_);
}

double Polynomial::max_root_abs() const {
  double m = 0.0;
  for (const auto& r : z_roots()) m = std::max(m, std::abs(r));
  return m;
}

std::string Polynomial::to_string(char variable, int precision) const {
  std::string s;
  for (std::size_t i = 0; i < c_.size(); ++i) {
    const double v = c_[i];
    if (v == 0.0 && c_.size() > 1) continue;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision + 1, std::abs(v));
    if (s.empty()) s += v < 0 ? "-" : "";
    else s += v < 0 ? " - " : " + ";
    s += buf;
    if (i == 1) s += std::string(1, variable);
    if (i > 1) s += std::string(1, variable) + "^" + std::to_string(i);
  }
  return s.empty() ? "0" : s;
}

std::vector<std::complex<double>> roots_descending(const std::vector<double>& c) {
  std::size_t first = 0;
  while (first < c.size() && c[first] == 0.0) ++first;
  if (first + 1 >= c.size()) return {};
  const std::size_t n = c.size() - first - 1;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (std::size_t j = 0; j < n; ++j) companion(0, static_cast<Eigen::Index>(j)) = -c[first + 1 + j] / c[first];
  for (std::size_t i = 1; i < n; ++i) companion(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i - 1)) = 1.0;
  Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, /*computeEigenvectors=*/false);
  std::vector<std::complex<double>> roots;
  roots.reserve(n);
  for (Eigen::Index i = 0; i < solver.eigenvalues().size(); ++i) roots.push_back(solver.eigenvalues()[i]);
  std::sort(roots.begin(), roots.end(), [](auto a, auto b) { return std::abs(a) > std::abs(b); });
  return roots;
}

}  // namespace epa::core
