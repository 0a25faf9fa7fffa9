#pragma once
// The HTML report of `epa diagnose`: the verdict in words, recorded vs nominal vs augmented model
// on one held-out run, the gap per regime before and after, the candidates and the per-run gaps,
// drawn with svg_chart and inlined, so the file opens on its own.
#include <string>

#include "diag/gap_report.hpp"

namespace epa::report {

std::string render_diagnosis_html(const diag::GapReport& report);

}  // namespace epa::report
