#pragma once
// How well an ARX model explains data, in the quantities the System Identification toolbox
// reports (the paper's "best fit", "loss function" and "FPE"):
//
//   fit %  = 100 (1 - ||y - yhat|| / ||y - mean(y)||)         (NRMSE fit, as `compare`)
//   loss V = (1/N) sum e(k)^2                                  (e: one-step residual, N rows)
//   FPE    = V (1 + d/N) / (1 - d/N)                           (Akaike's final prediction error)
//   AIC    = N ln V + 2 d                                      (d = na + nb parameters)
//
// The toolbox's "raw" AIC adds N (ln 2 pi + 1), the same for every order, so rankings agree.
// Fits are pooled over segments: the norms and the mean run over all scored samples together.
//
// yhat is either the one-step prediction (measured y in the regressors) or the free-run
// simulation (the model's own past outputs; only u from the data). The plant integrates, so a
// small gain error shows up as drift in the simulation that the one-step fit hides: the simulation
// fit is the honest one, and the one order selection ranks by. A simulation starts at sample
// `first` of each segment from the past y(first-1), ..., y(first-na) that makes its first
// kInitialStateSamples outputs follow the measurements best (least squares; initial_past()).
// Taken as measured, the noise of those na samples starts a model that integrates with a velocity
// it carries as an offset ever after: on a physics run whose piston rests at the start, the two
// samples before it differ by 0.18 mm of noise, and the validation fits of the orders with na = 2
// read 3 points higher from them (68.8 against 65.9 %; for better or worse, by chance).
// On noise-free data from the model itself the estimate is the true past, and the fit 100 %.
// Not over the whole run, as the toolbox's `compare` estimates the initial state: that fits each
// model the constant offset that suits its errors best, and more of it the higher its order (na
// values to fit), which moved order selection to orders of 4 whose designs were unstable.
#include <cstddef>
#include <vector>

#include "ident/arx_estimator.hpp"
#include "ident/ident_data.hpp"

namespace epa::ident {

// yhat(k) = one-step prediction for k >= first (first >= model's first_row); y(k) before.
std::vector<double> predict_one_step(const ArxModel& model, const Segment& segment, std::size_t first);

inline constexpr std::size_t kInitialStateSamples = 20;  // 0.1 s at 5 ms

// The past outputs (y(first-1) first, na of them) a free run from sample `first` starts from: the
// least-squares fit of its first kInitialStateSamples outputs to the measurements; the measured
// past itself when fewer samples follow or the model diverges. `first` >= the model's first_row().
std::vector<double> initial_past(const ArxModel& model, const Segment& segment, std::size_t first);

// Free-run simulation for k >= first, from initial_past(); y(k) before. A diverging model is
// stopped at |yhat| > 1e12 (the rest is left at the last value), so its fit is hugely negative but
// finite.
std::vector<double> simulate_free_run(const ArxModel& model, const Segment& segment, std::size_t first);

struct Fit {
  double one_step_pct = 0.0;
  double simulation_pct = 0.0;
};

// Both fits over samples k >= first of every segment (first is raised to the model's first_row).
Fit fit_percent(const ArxModel& model, const std::vector<Segment>& segments, std::size_t first);

// The NRMSE fit of predictions against measurements, pooled over segments from `first` on.
double nrmse_fit_percent(const std::vector<Segment>& segments, const std::vector<std::vector<double>>& yhat,
                         std::size_t first);

struct InformationCriteria {
  double loss = 0.0;  // V
  double fpe = 0.0;
  double aic = 0.0;
};

InformationCriteria information_criteria(double loss, std::size_t N, int d);

}  // namespace epa::ident
