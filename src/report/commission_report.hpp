#pragma once
// The commissioning report (`epa commission --report`, the page's panel): one HTML document with
// the verdict, the experiment, the fit, the design, and the simulated and measured verification
// moves side by side, drawn with svg_chart.
#include <string>

#include "commission/commission_sequence.hpp"

namespace epa::report {

std::string commission_report_html(const commission::CommissionOutcome& outcome);

}  // namespace epa::report
