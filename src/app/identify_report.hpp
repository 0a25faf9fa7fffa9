#pragma once
// What `epa identify` prints and draws: the identified model next to the paper's eq 9-10, its fits,
// and measured vs model output of the runs (the paper's figure 5).
#include <ostream>
#include <string>
#include <vector>

#include "core/hammerstein_model.hpp"
#include "core/run.hpp"
#include "ident/arx_metrics.hpp"
#include "ident/hammerstein_fit.hpp"
#include "ident/ident_data.hpp"

namespace epa::app {

struct IdentifiedRun {
  std::string path;
  core::Run run;
  std::vector<ident::Segment> segments;  // split at the end stops, y in sensor V
};

struct ModelFitSummary {
  ident::Fit estimation, validation;  // of the whole Hammerstein model (dead zone + ARX)
  bool validated = false;             // validation runs were given
};

ModelFitSummary summarise_fit(const ident::HammersteinFit& fit, const std::vector<ident::Segment>& estimation,
                              const std::vector<ident::Segment>& validation);

// Steady piston speed per volt of valve command beyond a break point, mm/s per V:
// slope * B(1) / (-A'(1)) * mm_per_volt / Ts, where -A'(1) = -sum i a_i is A(q) / (1 - q) at q = 1
// for an integrating A. Independent of the normalisation and of the orders, so it compares any
// identified model with the paper's.
double piston_speed_mm_s_per_v(const core::HammersteinModel& model, double slope);

// The model, its fits, and the comparison with eq 9-10 (break points, m_r/m_l, speeds, slopes on
// the paper's normalisation, and the coefficients when the orders are eq 9's).
void print_identified_model(std::ostream& out, const ident::HammersteinFit& fit, const core::HammersteinModel& model,
                            const ModelFitSummary& summary, double m_l);

// Per run (at most kMaxPlottedRuns): measured position vs the model's free-run simulation, and the
// valve command with the identified dead band shaded.
inline constexpr std::size_t kMaxPlottedRuns = 4;
std::string render_identification_plot(const std::vector<IdentifiedRun>& runs, const ident::HammersteinFit& fit,
                                       const core::HammersteinModel& model, bool validation);

}  // namespace epa::app
