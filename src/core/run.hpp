#pragma once
// One recorded or simulated run, column-wise (what epa-run/1 files hold, docs/formats.md).
// Sample k is at t_s[k] = k * Ts: the position y_mm[k] was read, then u_V[k] was applied
// and held until k+1 (sample, compute, hold; no extra computation delay).
#include <string>
#include <utility>
#include <vector>

namespace epa::core {

struct Run {
  double Ts = 0.005;  // sample time, s
  // `# key=value` metadata other than Ts, in file order (controller, source, anything else).
  std::vector<std::pair<std::string, std::string>> metadata;

  std::vector<double> t_s;   // time, s (required)
  std::vector<double> y_mm;  // measured position (required)
  std::vector<double> u_V;   // valve command actually applied (required)
  std::vector<double> r_mm;  // reference (optional: empty when absent)
  std::vector<double> uc_V;  // controller output before dead-zone compensation (optional)

  std::size_t size() const { return t_s.size(); }
  // How long it lasts: each sample is held for Ts.
  double duration_s() const { return static_cast<double>(size()) * Ts; }

  // Value of a metadata key, or "" when absent.
  std::string meta(const std::string& key) const {
    for (const auto& [k, v] : metadata)
      if (k == key) return v;
    return "";
  }
  void set_meta(const std::string& key, const std::string& value) {
    for (auto& [k, v] : metadata)
      if (k == key) { v = value; return; }
    metadata.emplace_back(key, value);
  }
};

}  // namespace epa::core
