#pragma once
// The whole identification behind `epa identify`, as one call (so the commissioning sequence can
// run the same thing):
//   1. the dead zone by the swarm with least squares inside (hammerstein_fit.hpp), for orders that
//      nest every candidate of the search (options.swarm.orders);
//   then with the simulation criterion (the default):
//   2. the dead band read off the excitation's slow ramps (ramp_reading.hpp): the band each break
//      point must stay in;
//   3. every order of the search refined on the free-run simulation error from the swarm's dead
//      zone, and one chosen (simulation_refinement.hpp, the rule of order_selection.hpp);
//   or with the one-step criterion (`--criterion one-step`):
//   2'. the order chosen on least squares through the swarm's dead zone;
//   3'. the dead zone polished for that order.
// A side of the dead zone the data never drive beyond is an error that says what to record.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "ident/hammerstein_fit.hpp"
#include "ident/ident_data.hpp"
#include "ident/order_selection.hpp"
#include "ident/ramp_reading.hpp"

namespace epa::ident {

struct IdentificationOptions {
  OrderSearch search;
  HammersteinFitOptions swarm;  // orders: ones that nest every candidate of the search; m_l: the normalisation
  FitCriterion criterion = FitCriterion::kSimulation;
  double window_s = 0.0;        // simulation criterion: restart from the measured y every window_s (0: whole runs)
  bool ramp_band = true;        // simulation criterion: keep the break points in the ramps' band (false: free)
  double Ts = 0.005;            // of the runs, s
  double mm_per_volt = 50.0;    // the model's sensor scale (segments hold y in sensor volts)
};

struct Identification {
  HammersteinFit fit;                        // the chosen model, on the m_l normalisation
  OrderSelection selection;                  // the order table (refined models with the simulation criterion)
  std::optional<DeadBandReading> dead_band;  // what the ramps showed (simulation criterion with ramp_band)
  std::size_t swarm_evaluations = 0;         // least-squares fits in step 1

  core::HammersteinModel model(double Ts, double mm_per_volt) const { return fit.model(Ts, mm_per_volt); }
};

// `estimation` and `validation` hold the raw valve command; `validation` may be empty (the order is
// then chosen on the estimation runs). Errors: those of the steps, and a side not identified.
core::Result<Identification> identify_hammerstein(const std::vector<Segment>& estimation,
                                                  const std::vector<Segment>& validation,
                                                  const IdentificationOptions& options);

// The message for a fit whose right or left side is not identified (names the evidence and what to
// record instead).
std::string unidentified_side_message(const HammersteinFit& fit);

}  // namespace epa::ident
