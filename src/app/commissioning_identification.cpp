#include "app/commissioning_identification.hpp"

#include <cmath>
#include <cstdio>

#include "app/identify_command.hpp"
#include "app/model_scope.hpp"
#include "core/units.hpp"
#include "ident/arx_estimator.hpp"
#include "ident/arx_metrics.hpp"
#include "ident/hammerstein_identification.hpp"
#include "ident/stick_slip_fit.hpp"
#include "report/identify_report.hpp"

namespace epa::app {

namespace {

// `epa identify`'s defaults: the order search, the swarm, the simulation criterion with the ramps' band.
core::Result<ident::IdentificationOptions> default_options(double Ts, double mm_per_volt) {
  const IdentifyOptions cli;
  auto na = ident::parse_order_range(cli.na, "--na");
  auto nb = ident::parse_order_range(cli.nb, "--nb");
  auto nk = ident::parse_order_range(cli.nk, "--nk");
  for (const auto* r : {&na, &nb, &nk})
    if (!*r) return r->error();
  ident::IdentificationOptions o;
  o.search = {.na = *na, .nb = *nb, .nk = *nk, .tolerance_pct = cli.tolerance_pct};
  o.swarm.orders = {.na = na->hi, .nb = nb->hi + nk->hi - nk->lo, .nk = nk->lo};
  o.swarm.seed = cli.seed;
  o.swarm.particles = cli.particles;
  o.swarm.generations = cli.generations;
  o.swarm.m_l = cli.m_l;
  o.criterion = ident::FitCriterion::kSimulation;
  o.ramp_band = true;
  o.Ts = Ts;
  o.mm_per_volt = mm_per_volt;
  return o;
}

core::Result<std::vector<ident::Segment>> segments_of(const core::Run& run, const std::string& name, double mm_per_volt, bool estimation) {
  auto segments = ident::split_run(run, name, {.mm_per_volt = mm_per_volt});
  const ident::ExcitationCheck check{.need_both_directions = estimation};
  if (auto s = ident::check_excitation(segments, name, check, mm_per_volt); !s) return s.error();
  return segments;
}

}  // namespace

commission::Identify identify_for_commissioning(double mm_per_volt) {
  return [mm_per_volt](const std::vector<core::Run>& estimation, const core::Run& validation) -> core::Result<commission::IdentifiedModel> {
    if (estimation.empty()) return core::invalid_argument("no estimation run");
    const double Ts = estimation.front().Ts;
    std::vector<ident::Segment> est, val;
    for (std::size_t i = 0; i < estimation.size(); ++i) {
      if (!core::same_sample_time(estimation[i].Ts, Ts)) return core::invalid_argument("the excitation runs differ in Ts");
      auto s = segments_of(estimation[i], "excitation run " + std::to_string(i + 1), mm_per_volt, true);
      if (!s) return s.error();
      est.insert(est.end(), s->begin(), s->end());
    }
    auto v = segments_of(validation, "held-out excitation run", mm_per_volt, false);
    if (!v) return v.error();
    val = std::move(*v);
    auto options = default_options(Ts, mm_per_volt);
    if (!options) return options.error();
    auto identified = ident::identify_hammerstein(est, val, *options);
    if (!identified) return identified.error();
    const core::HammersteinModel model = identified->model(Ts, mm_per_volt);
    if (auto s = model.validate(); !s) return core::numerical_error("the identified model is not valid: " + s.error().message);
    const report::ModelFitSummary fits = report::summarise_fit(identified->fit, est, val, identified->selection.first);

    commission::IdentifiedModel out{model, fits.estimation.simulation_pct, fits.validation.simulation_pct, {}, {}};
    std::vector<const core::Run*> estimation_runs;
    for (const auto& run : estimation) estimation_runs.push_back(&run);
    out.identified_drive_v = identified_drive_v(estimation_runs);  // the commands the model was identified on
    // The held-out run's free run, where its first segment lies (NaN elsewhere: end stops).
    out.validation_simulated_mm.assign(validation.size(), std::nan(""));
    const auto ud = ident::through_dead_zone(val, identified->fit.dead_zone);
    if (!ud.empty()) {
      const auto yhat = ident::simulate_free_run(identified->fit.arx.model, ud.front(), fits.first_sample);
      const auto first = static_cast<std::size_t>(std::llround((ud.front().t0_s - validation.t_s.front()) / Ts));
      for (std::size_t k = 0; k < yhat.size() && first + k < out.validation_simulated_mm.size(); ++k)
        out.validation_simulated_mm[first + k] = yhat[k] * mm_per_volt;
    }
    char buf[320];
    std::snprintf(buf, sizeof buf, "ARX %s, dead zone [%.3f, %.3f] V, free-run fit %.1f %% on the estimation runs, %.1f %% on the held-out run",
                  identified->fit.arx.model.orders.to_string().c_str(), model.dead_zone.b_l, model.dead_zone.b_r,
                  out.estimation_fit_pct, out.validation_fit_pct);
    out.summary = buf;

    // The stick-slip model beside it, as epa identify fits it; the one that follows the held-out run
    // better describes the axis (pp-traj then arrives while sliding, the simulation runs on it).
    ident::StickSlipFitOptions fit_options;
    fit_options.Ts = Ts;
    fit_options.mm_per_volt = mm_per_volt;
    auto stick = ident::identify_stick_slip(est, val, model, identified->fit.arx.model.orders.nk, fit_options);
    if (!stick) return core::numerical_error("the stick-slip model: " + stick.error().message);
    out.stick_slip = stick->fit.params;
    out.stick_slip_validation_fit_pct = stick->validation_pct;
    out.axis_model = report::axis_model_verdict(*stick, fits);
    // How far its terms move over parts of the held-out run, as epa identify writes it (app/model_scope.hpp).
    const core::Run* const validation_run[] = {&validation};
    out.stick_slip_spread = model_spread(*out.stick_slip, Ts, validation_run, *out.identified_drive_v);
    std::snprintf(buf, sizeof buf, "; stick-slip model: free-run fit %.1f %% on the held-out run%s", stick->validation_pct,
                  out.axis_model == core::AxisModel::kStickSlip ? " (describes the axis)" : "");
    out.summary += buf;
    return out;
  };
}

}  // namespace epa::app
