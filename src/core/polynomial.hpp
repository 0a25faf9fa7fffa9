#pragma once
// Polynomials in the backward shift q = z^-1: coefficient i multiplies q^i, so
// A = 1 - 0.9094q - ... is {1, -0.9094, ...}. Used off the control loop (design, analysis);
// the loop itself uses fixed-size arrays (control/rst_law.hpp).
#include <complex>
#include <initializer_list>
#include <string>
#include <vector>

namespace epa::core {

class Polynomial {
 public:
  Polynomial() = default;
  Polynomial(std::initializer_list<double> coefficients) : c_(coefficients) {}
  explicit Polynomial(std::vector<double> coefficients) : c_(std::move(coefficients)) {}

  const std::vector<double>& coefficients() const { return c_; }
  std::size_t size() const { return c_.size(); }
  double operator[](std::size_t i) const { return i < c_.size() ? c_[i] : 0.0; }

  // Highest power of q with a non-zero coefficient; -1 for the zero polynomial.
  int degree() const;

  Polynomial operator+(const Polynomial& other) const;
  Polynomial operator-(const Polynomial& other) const;
  Polynomial operator*(const Polynomial& other) const;
  Polynomial operator*(double factor) const;

  // Value at q (so at z = 1/q); P(1) is the static gain term.
  double at(double q) const;
  std::complex<double> at(std::complex<double> q) const;

  // Coefficients in descending powers of z for a polynomial of z-degree `z_degree`:
  // z^n P(z^-1). With z_degree = size()-1 that is the same list (eq 14/15 print it this way).
  std::vector<double> descending_z(std::size_t z_degree) const;

  // Roots in z of z^n P(z^-1), n = size()-1 (trailing zero coefficients give roots at z = 0).
  std::vector<std::complex<double>> z_roots() const;

  // The largest |root| in z; 0 for a constant.
  double max_root_abs() const;

  std::string to_string(char variable = 'q', int precision = 4) const;

 private:
  std::vector<double> c_;
};

// Roots of a polynomial given in descending powers (c[0] x^n + ... + c[n]), via the companion
// matrix's eigenvalues. Leading zeros are dropped.
std::vector<std::complex<double>> roots_descending(const std::vector<double>& c);

}  // namespace epa::core
