#pragma once
// The Jury stability test for a discrete characteristic polynomial P(z), returning the verdict
// and the table it was decided by (not just max |root|), so a report can show its working.
#include <string>
#include <vector>

namespace epa::control {

enum class Stability { kStable, kMarginal, kUnstable };
const char* to_string(Stability s);

struct JuryCondition {
  std::string text;  // "lhs > rhs" as printed: "P(1) > 0", "|a0| > |a5|", "|b0| > |b4|"
  double lhs = 0.0;
  double rhs = 0.0;
  bool holds = false;
  bool boundary = false;  // equal within tolerance: a root on the unit circle
};

struct JuryResult {
  Stability verdict = Stability::kUnstable;
  // Rows of the table, in descending powers of z: each reduced row followed by its reverse.
  std::vector<std::vector<double>> table;
  std::vector<JuryCondition> conditions;
};

// `p` is P in descending powers of z (p[0] z^n + ... + p[n]); leading zeros are dropped and the
// sign is normalised so that p[0] > 0. Conditions: P(1) > 0, (-1)^n P(-1) > 0, and at each
// reduction level |first| > |last| (Schur-Cohn-Jury row reduction b_k = a_0 a_k - a_m a_{m-k}).
// A condition that fails by no more than `relative_tolerance` (relative to the row's scale) is a
// boundary case: the verdict is then kMarginal instead of kUnstable.
JuryResult jury_test(const std::vector<double>& p, double relative_tolerance = 1e-9);

}  // namespace epa::control
