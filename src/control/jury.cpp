#include "control/jury.hpp"

#include <algorithm>
#include <cmath>

namespace epa::control {

const char* to_string(Stability s) {
  switch (s) {
    case Stability::kStable: return "stable";
    case Stability::kMarginal: return "marginal";
    case Stability::kUnstable: return "unstable";
  }
  return "?";
}

namespace {

double scale_of(const std::vector<double>& a) {
  double s = 0.0;
  for (double v : a) s = std::max(s, std::abs(v));
  return s > 0.0 ? s : 1.0;
}

// Records "lhs > rhs" (strict): holds, or is a boundary case within tolerance * scale.
void add_condition(JuryResult& r, std::string text, double lhs, double rhs, double scale, double tol) {
  const double margin = lhs - rhs;
  const bool boundary = std::abs(margin) <= tol * scale;
  r.conditions.push_back({std::move(text), lhs, rhs, !boundary && margin > 0.0, boundary});
}

}  // namespace

JuryResult jury_test(const std::vector<double>& p_in, double tol) {
  JuryResult result;
  std::vector<double> a(std::find_if(p_in.begin(), p_in.end(), [](double v) { return v != 0.0; }), p_in.end());
  if (a.size() < 2) {  // a constant has no roots
    result.verdict = a.empty() ? Stability::kUnstable : Stability::kStable;
    return result;
  }
  if (a[0] < 0) for (double& v : a) v = -v;
  const std::size_t n = a.size() - 1;
  const double scale = scale_of(a);

  double p1 = 0.0, pm1 = 0.0;
  for (std::size_t i = 0; i <= n; ++i) {
    p1 += a[i];
    pm1 += a[i] * (((n - i) % 2 == 0) ? 1.0 : -1.0);  // P(-1)
  }
  add_condition(result, "P(1) > 0", p1, 0.0, scale, tol);
  add_condition(result, "(-1)^" + std::to_string(n) + " P(-1) > 0", (n % 2 == 0 ? 1.0 : -1.0) * pm1, 0.0, scale, tol);

  // Row reduction: each level must have |last| < |first|; the next row is one shorter.
  const char row_letter[] = "abcdefghijklmnop";
  std::vector<double> row = a;
  for (std::size_t level = 0; row.size() >= 2; ++level) {
    result.table.push_back(row);
    result.table.emplace_back(row.rbegin(), row.rend());
    const std::size_t m = row.size() - 1;
    const char letter = row_letter[std::min<std::size_t>(level, sizeof row_letter - 2)];
    add_condition(result, std::string("|") + letter + "0| > |" + letter + std::to_string(m) + "|",
                  std::abs(row[0]), std::abs(row[m]), scale_of(row), tol);
    if (!result.conditions.back().holds) break;  // later rows are degenerate: the verdict is known
    std::vector<double> next(m);
    for (std::size_t k = 0; k < m; ++k) next[k] = row[0] * row[k] - row[m] * row[m - k];
    row = std::move(next);
  }

  const bool any_boundary = std::any_of(result.conditions.begin(), result.conditions.end(), [](const auto& c) { return c.boundary; });
  const bool any_failed = std::any_of(result.conditions.begin(), result.conditions.end(),
                                      [](const auto& c) { return !c.holds && !c.boundary; });
  result.verdict = any_failed ? Stability::kUnstable : any_boundary ? Stability::kMarginal : Stability::kStable;
  return result;
}

}  // namespace epa::control
