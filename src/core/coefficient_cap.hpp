#pragma once
// The most coefficients a polynomial of a file may have (model A and B, controller F, G, H, T).
// The laws of this appliance have a handful; a design with thousands takes minutes and gigabytes
// (the Sylvester matrix grows with the square), so a file that asks for more is refused when read.
#include <cstddef>
#include <string>

#include "core/result.hpp"

namespace epa::core {

inline constexpr std::size_t kMaxPolynomialCoefficients = 64;

// "<where> has 100000 coefficients, more than the 64 a polynomial may have".
inline Status check_coefficient_count(std::size_t count, const std::string& where) {
  if (count <= kMaxPolynomialCoefficients) return ok();
  return parse_error(where + " has " + std::to_string(count) + " coefficients, more than the " +
                     std::to_string(kMaxPolynomialCoefficients) + " a polynomial may have");
}

}  // namespace epa::core
