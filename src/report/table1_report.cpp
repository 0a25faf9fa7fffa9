#include "report/table1_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "core/paper_reference.hpp"

namespace epa::report {

namespace {

using control::ControllerKind;

std::string cell(std::optional<double> v, const char* fmt, const char* missing = "never") {
  if (!v) return missing;
  char buf[32];
  std::snprintf(buf, sizeof buf, fmt, *v);
  return buf;
}

std::string paper_cell(double v, const char* fmt) {
  if (v == core::paper::kGreaterThan5) return ">5";
  return cell(v, fmt);
}

const core::paper::Table1Row* paper_row(double step_mm, ControllerKind kind) {
  for (const auto& e : core::paper::kTable1) {
    if (std::abs(e.step_mm - step_mm) > 1e-9) continue;
    switch (kind) {
      case ControllerKind::kPp: return &e.pp;
      case ControllerKind::kPpNgidz: return &e.ngidz;
      case ControllerKind::kPpFfidz: return &e.ffidz;
      case ControllerKind::kPpTraj: return nullptr;  // not in the paper
    }
  }
  return nullptr;
}

const SimulationCase* find(const std::vector<SimulationCase>& cases, double step_mm, ControllerKind kind) {
  for (const auto& c : cases)
    if (c.kind == kind && c.step_mm == step_mm) return &c;
  return nullptr;
}

}  // namespace

void print_table1_comparison(std::ostream& out, const std::vector<SimulationCase>& cases) {
  std::vector<double> steps;
  std::vector<ControllerKind> kinds;
  for (const auto& c : cases) {
    if (std::find(steps.begin(), steps.end(), c.step_mm) == steps.end()) steps.push_back(c.step_mm);
    if (std::find(kinds.begin(), kinds.end(), c.kind) == kinds.end()) kinds.push_back(c.kind);
  }
  char line[256];
  std::string head = "step      criterion           ";
  std::string sub = "                              ";
  for (auto k : kinds) {
    std::snprintf(line, sizeof line, "%-20s", std::string(control::display_name(k)).c_str());
    head += line;
    sub += "   paper       sim  ";
  }
  out << head << "\n" << sub << "\n";

  struct Criterion {
    const char* name;
    const char* fmt;
  };
  const Criterion criteria[] = {{"rise T_r (s)", "%.2f"},     {"settling T_s (s)", "%.2f"}, {"e_ss (mm)", "%.2f"},
                                {"overshoot OS (%)", "%.1f"}, {"valve sign changes", "%.0f"}};
  for (double step : steps) {
    for (std::size_t ci = 0; ci < std::size(criteria); ++ci) {
      std::string row;
      std::snprintf(line, sizeof line, "%-10s%-20s", ci == 0 ? (cell(step, "%g") + " mm").c_str() : "", criteria[ci].name);
      row += line;
      for (auto k : kinds) {
        const auto* sim = find(cases, step, k);
        const auto* paper = paper_row(step, k);
        std::string p = "-", s = "-";
        if (paper) {
          const double values[] = {paper->rise_s, paper->settling_s, paper->ess_mm, paper->overshoot_pct};
          if (ci < 4) p = paper_cell(values[ci], criteria[ci].fmt);
        }
        if (sim) {
          const auto& m = sim->result.metrics;
          switch (ci) {
            case 0: s = cell(m.rise_s, criteria[ci].fmt); break;
            case 1: s = cell(m.settling_s, criteria[ci].fmt); break;
            case 2: s = cell(m.ess_mm, criteria[ci].fmt); break;
            case 3: s = cell(m.overshoot_pct, criteria[ci].fmt, "-"); break;
            default: s = cell(static_cast<double>(sim->result.valve_sign_changes), criteria[ci].fmt); break;
          }
        }
        std::snprintf(line, sizeof line, "%8s  %8s  ", p.c_str(), s.c_str());
        row += line;
      }
      out << row << "\n";
    }
    out << "\n";
  }
  out << "paper: Table 1 (experiments on the rig); sim: this simulation. \"never\": the response never\n"
         "reached 90 % of its final value or never settled; \"-\": not applicable (the piston never moved).\n";
}

}  // namespace epa::report
