#pragma once
// Polynomial coefficients as the store keeps them: a JSON array text, full double precision.
#include <string>

#include "core/polynomial.hpp"
#include "core/result.hpp"

namespace epa::store {

std::string to_json_text(const core::Polynomial& p);
core::Result<core::Polynomial> polynomial_from_json_text(const std::string& text, const std::string& what);

}  // namespace epa::store
