#pragma once
// What `epa identify` prints and draws: the identified model next to the paper's eq 9-10, its fits,
// and measured vs model output of the runs (the paper's figure 5).
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/hammerstein_model.hpp"
#include "core/model_file.hpp"
#include "core/run.hpp"
#include "ident/arx_metrics.hpp"
#include "ident/hammerstein_fit.hpp"
#include "ident/ident_data.hpp"
#include "ident/stick_slip_fit.hpp"

namespace epa::report {

struct IdentifiedRun {
  std::string path;
  core::Run run;
  std::vector<ident::Segment> segments;  // split at the end stops, y in sensor V
};

struct ModelFitSummary {
  ident::Fit estimation, validation;  // of the whole Hammerstein model (dead zone + ARX)
  bool validated = false;             // validation runs were given
  std::size_t first_sample = 0;       // scored from this sample of each segment on
};

// Scored from `first_sample` of each segment on: the order table's common first sample
// (OrderSelection::first), so the chosen order reads here as in its row. A free run of an
// integrating model carries the noise of the samples it starts from as an offset for the whole
// run, so on the same model the figure moves with where it starts (70.20 % from sample 5, 68.08 %
// from sample 2, on `epa excite --plant physics` runs).
ModelFitSummary summarise_fit(const ident::HammersteinFit& fit, const std::vector<ident::Segment>& estimation,
                              const std::vector<ident::Segment>& validation, std::size_t first_sample);


// The model, its fits, and the comparison with eq 9-10 (break points, m_r/m_l, speeds, slopes on
// the paper's normalisation, and the coefficients when the orders are eq 9's).
void print_identified_model(std::ostream& out, const ident::HammersteinFit& fit, const core::HammersteinModel& model,
                            const ModelFitSummary& summary, double m_l);

// Per run (at most kMaxPlottedRuns): measured position vs the model's free-run simulation (and the
// stick-slip model's, when given), and the valve command with the identified dead band shaded.
inline constexpr std::size_t kMaxPlottedRuns = 4;
std::string render_identification_plot(const std::vector<IdentifiedRun>& runs, const ident::HammersteinFit& fit,
                                       const core::HammersteinModel& model, bool validation,
                                       const std::optional<core::StickSlipParams>& stick_slip = std::nullopt);

// The stick-slip model's section of `epa identify`: its parameters in physical units, where its
// piston starts to move on a slow ramp, and its free-run fits beside the Hammerstein model's.
void print_stick_slip(std::ostream& out, const ident::StickSlipIdentification& r, const ModelFitSummary& hammerstein);

// Which model describes the axis: the one whose free run follows the held-out runs (or, with none,
// the estimation runs) better. The model file records it (axis_model); pp-traj arrives while sliding
// on a stick-slip axis. The design takes the Hammerstein model either way.
core::AxisModel axis_model_verdict(const ident::StickSlipIdentification& r, const ModelFitSummary& hammerstein);
// The same for the tuning store's fit figures (`--save`).
nlohmann::json stick_slip_json(const ident::StickSlipIdentification& r, bool validated);

}  // namespace epa::report
