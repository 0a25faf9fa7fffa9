#include "store/polynomial_json.hpp"

#include <nlohmann/json.hpp>

namespace epa::store {

std::string to_json_text(const core::Polynomial& p) { return nlohmann::json(p.coefficients()).dump(); }

core::Result<core::Polynomial> polynomial_from_json_text(const std::string& text, const std::string& what) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_array()) return core::parse_error(what + " is not a JSON array of numbers: " + text);
  std::vector<double> c;
  for (const auto& v : j) {
    if (!v.is_number()) return core::parse_error(what + " holds a value that is not a number: " + text);
    c.push_back(v.get<double>());
  }
  return core::Polynomial(std::move(c));
}

}  // namespace epa::store
