#include "report/identify_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/format.hpp"
#include "core/paper_reference.hpp"
#include "report/svg_chart.hpp"

namespace epa::report {

ModelFitSummary summarise_fit(const ident::HammersteinFit& fit, const std::vector<ident::Segment>& est,
                              const std::vector<ident::Segment>& val, std::size_t first_sample) {
  ModelFitSummary s;
  const std::size_t first = std::max(first_sample, fit.arx.model.orders.first_row());
  s.first_sample = first;
  s.estimation = ident::fit_percent(fit.arx.model, ident::through_dead_zone(est, fit.dead_zone), first);
  s.validated = !val.empty();
  if (s.validated) s.validation = ident::fit_percent(fit.arx.model, ident::through_dead_zone(val, fit.dead_zone), first);
  return s;
}

namespace {

constexpr double kDetailWindowS = 5.0;

std::string coefficients(const core::Polynomial& p) {
  std::string s = "[";
  for (std::size_t i = 0; i < p.size(); ++i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%s%.5g", i ? ", " : "", p[i]);
    s += buf;
  }
  return s + "]";
}

void row(std::ostream& out, std::string label, double ours, double paper, const char* unit = "") {
  if (label.size() < 34) label.resize(34, ' ');
  char numbers[64];
  std::snprintf(numbers, sizeof numbers, " %12.4f %12.4f ", ours, paper);
  out << "  " << label << numbers << unit << "\n";
}

}  // namespace

void print_identified_model(std::ostream& out, const ident::HammersteinFit& fit, const core::HammersteinModel& model,
                            const ModelFitSummary& s, double m_l) {
  const auto& dz = model.dead_zone;
  const auto paper = core::paper::model();
  const auto& pdz = paper.dead_zone;
  char buf[400];
  out << "\nIdentified model (" << fit.arx.model.orders.to_string() << ", y in sensor volts, " << model.mm_per_volt
      << " mm/V, Ts = " << model.Ts << " s):\n"
      << "  A = " << model.A.to_string('q', 5) << "\n  B = " << model.B.to_string('q', 5) << "\n";
  std::snprintf(buf, sizeof buf, "  dead zone: m_r = %.5f, m_l = %.5f, b_r = %.5f V, b_l = %.5f V\n", dz.m_r, dz.m_l,
                dz.b_r, dz.b_l);
  out << buf;
  std::snprintf(buf, sizeof buf,
                "  fit (free-run simulation / one-step prediction, scored from sample %zu of each run as the order table is): "
                "estimation %.2f %% / %.2f %%",
                s.first_sample, s.estimation.simulation_pct, s.estimation.one_step_pct);
  out << buf;
  if (s.validated) {
    std::snprintf(buf, sizeof buf, ", validation %.2f %% / %.2f %%", s.validation.simulation_pct, s.validation.one_step_pct);
    out << buf;
  }
  if (fit.criterion == ident::FitCriterion::kSimulation)
    std::snprintf(buf, sizeof buf,
                  "\n  simulation error V = %.4e (%.3f mm RMS; %.4e at the least-squares start), %zu least-squares fits "
                  "and simulations\n",
                  fit.arx.loss, std::sqrt(fit.arx.loss) * model.mm_per_volt, fit.best_loss_after_swarm, fit.evaluations);
  else
    std::snprintf(buf, sizeof buf, "\n  loss V = %.4e, %zu least-squares fits in the dead-zone search\n", fit.arx.loss,
                  fit.evaluations);
  out << buf;

  out << "\nCompared with the paper (eq 9-10):          identified        paper\n";
  row(out, "right break point b_r", dz.b_r, pdz.b_r, "V");
  row(out, "left break point b_l", dz.b_l, pdz.b_l, "V");
  row(out, "slope ratio m_r / m_l", dz.m_r / dz.m_l, pdz.m_r / pdz.m_l);
  row(out, "speed per V beyond b_r", core::piston_speed_mm_s_per_v(model, dz.m_r), core::piston_speed_mm_s_per_v(paper, pdz.m_r), "mm/s");
  row(out, "speed per V beyond b_l", core::piston_speed_mm_s_per_v(model, dz.m_l), core::piston_speed_mm_s_per_v(paper, pdz.m_l), "mm/s");
  std::snprintf(buf, sizeof buf, "m_r (normalised: m_l := %g)", m_l);
  row(out, buf, dz.m_r, pdz.m_r);
  row(out, "m_l", dz.m_l, pdz.m_l);
  if (fit.arx.model.orders == ident::ArxOrders{.na = 3, .nb = 3, .nk = 1}) {
    out << "  A  " << coefficients(model.A) << "   paper " << coefficients(paper.A) << "\n"
        << "  B  " << coefficients(model.B) << "   paper " << coefficients(paper.B) << "\n";
  } else {
    out << "  (eq 9 has na=3 nb=3 nk=1: compare the speeds above and the responses, not the coefficients)\n";
  }
  std::snprintf(buf, sizeof buf,
                "  Normalisation: data determine only the products m_r B and m_l B (and b_r, b_l, m_r/m_l). The\n"
                "  model fixes m_l = %g (the paper's value unless --m-l) and scales B to match, so the slopes and\n"
                "  B are on the paper's scale; the speeds above do not depend on this choice.\n",
                m_l);
  out << buf;
}

std::string render_identification_plot(const std::vector<IdentifiedRun>& runs, const ident::HammersteinFit& fit,
                                       const core::HammersteinModel& model, bool validation,
                                       const std::optional<core::StickSlipParams>& stick_slip) {
  std::vector<Panel> panels;
  const std::size_t first = fit.arx.model.orders.first_row();
  for (std::size_t r = 0; r < runs.size() && r < kMaxPlottedRuns; ++r) {
    const auto& run = runs[r];
    Series measured{"measured", "#000000", {}, {}, false}, simulated{"model (free run)", "#d62728", {}, {}, false};
    Series sticking{"stick-slip model (free run)", "#2ca02c", {}, {}, false};
    std::vector<std::vector<double>> yhat;
    const auto ud = ident::through_dead_zone(run.segments, fit.dead_zone);
    const auto stick_yhat = stick_slip ? ident::simulate_stick_slip(run.segments, *stick_slip, model.Ts, model.mm_per_volt)
                                       : std::vector<std::vector<double>>{};
    for (std::size_t i = 0; i < ud.size(); ++i) {
      yhat.push_back(ident::simulate_free_run(fit.arx.model, ud[i], first));
      for (std::size_t k = 0; k < ud[i].size(); ++k) {
        const double t = ud[i].t0_s + static_cast<double>(k) * model.Ts;
        measured.x.push_back(t), simulated.x.push_back(t);
        measured.y.push_back(ud[i].y[k] * model.mm_per_volt);
        simulated.y.push_back(yhat.back()[k] * model.mm_per_volt);
        if (stick_slip) sticking.x.push_back(t), sticking.y.push_back(stick_yhat[i][k] * model.mm_per_volt);
      }
      // A gap between segments (an end stop) breaks the lines.
      measured.x.push_back(NAN), measured.y.push_back(NAN), simulated.x.push_back(NAN), simulated.y.push_back(NAN);
      sticking.x.push_back(NAN), sticking.y.push_back(NAN);
    }
    char title[400];
    const int used = std::snprintf(title, sizeof title, "%s (%s): position, free-run fit %.1f %%", run.path.c_str(),
                                   validation ? "validation" : "estimation", ident::nrmse_fit_percent(ud, yhat, first));
    if (stick_slip && used > 0 && static_cast<std::size_t>(used) < sizeof title)
      std::snprintf(title + used, sizeof title - static_cast<std::size_t>(used), ", stick-slip model %.1f %%",
                    ident::nrmse_fit_percent(run.segments, stick_yhat, 0));
    std::vector<Series> lines{simulated, measured};
    if (stick_slip) lines.insert(lines.begin() + 1, sticking);
    Panel position{title, "time (s)", "position (mm)", lines, {}, {}, {}, {}, {}};
    Panel valve{"valve command", "time (s)", "valve command (V)", {}, {}, {}, {}, {}, {}};
    Series u{"u", "#1f77b4", run.run.t_s, run.run.u_V, false};
    valve.series.push_back(std::move(u));
    valve.bands.push_back({model.dead_zone.b_l, model.dead_zone.b_r, "identified dead band"});
    // A few seconds from the middle of the run, where the two lines can be told apart.
    const double t_mid = run.run.t_s.empty() ? 0.0 : 0.5 * (run.run.t_s.front() + run.run.t_s.back());
    Panel detail{run.path + ": detail", "time (s)", "position (mm)", lines, {}, t_mid, t_mid + kDetailWindowS, {}, {}};
    panels.push_back(std::move(position));
    panels.push_back(std::move(detail));
    panels.push_back(std::move(valve));
  }
  return render_svg("Measured and model output (" + fit.arx.model.orders.to_string() + ")", panels, 1, 1100, 280);
}

void print_stick_slip(std::ostream& out, const ident::StickSlipIdentification& r, const ModelFitSummary& hammerstein) {
  const auto& p = r.fit.params;
  const bool validated = !std::isnan(r.validation_pct);
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "  flow dead zone: b_r = %.4f V, b_l = %.4f V; the piston starts to move at %+.3f / %+.3f V on a %g V/s ramp\n"
                "  speed per V beyond them: %.1f / %.1f mm/s\n",
                p.break_right_v, p.break_left_v, r.ramp_right_v, r.ramp_left_v, ident::StickSlipIdentification::kRampVPerS,
                p.speed_right_mm_s_per_v, p.speed_left_mm_s_per_v);
  out << buf;
  std::snprintf(buf, sizeof buf,
                "  air spring %.1f rad/s, damping ratio %.3f; friction as the spring's wind-up: sliding %.2f mm, "
                "breakaway %.2f mm\n  spool lag %.1f ms, dead time %d sample(s)\n",
                p.spring_rad_s, p.damping_ratio, p.coulomb_mm, p.static_mm, 1e3 * p.spool_lag_s, p.delay_samples);
  out << buf;
  if (!validated)
    std::snprintf(buf, sizeof buf, "  free-run fit: estimation %.2f %% (the Hammerstein model: %.2f %%)\n", r.estimation_pct,
                  hammerstein.estimation.simulation_pct);
  else
    std::snprintf(buf, sizeof buf, "  free-run fit: estimation %.2f %%, validation %.2f %% (the Hammerstein model: %.2f %%, %.2f %%)\n",
                  r.estimation_pct, r.validation_pct, hammerstein.estimation.simulation_pct,
                  hammerstein.validation.simulation_pct);
  out << buf;
  std::snprintf(buf, sizeof buf, "  simulation error %.3f mm RMS on the estimation runs, %zu simulations\n",
                std::sqrt(r.fit.loss_mm2), r.fit.evaluations);
  out << buf;
  const bool stick = axis_model_verdict(r, hammerstein) == core::AxisModel::kStickSlip;
  out << (stick ? "  the stick-slip model follows the " : "  the Hammerstein model follows the ")
      << (validated ? "validation" : "estimation")
      << (stick ? " runs better: it describes the axis (the model file says so: pp-traj arrives while sliding; "
                  "epa design still takes the Hammerstein model)\n"
                : " runs better: this plant shows little stick-slip\n");
}

core::AxisModel axis_model_verdict(const ident::StickSlipIdentification& r, const ModelFitSummary& hammerstein) {
  const bool validated = !std::isnan(r.validation_pct);
  const double stick = validated ? r.validation_pct : r.estimation_pct;
  const double hamm = validated ? hammerstein.validation.simulation_pct : hammerstein.estimation.simulation_pct;
  return core::axis_model_from_fits(stick, hamm);
}

nlohmann::json stick_slip_json(const ident::StickSlipIdentification& r, bool validated) {
  const auto& p = r.fit.params;
  return {{"break_right_v", p.break_right_v},
          {"break_left_v", p.break_left_v},
          {"speed_right_mm_s_per_v", p.speed_right_mm_s_per_v},
          {"speed_left_mm_s_per_v", p.speed_left_mm_s_per_v},
          {"spring_rad_s", p.spring_rad_s},
          {"damping_ratio", p.damping_ratio},
          {"coulomb_mm", p.coulomb_mm},
          {"static_mm", p.static_mm},
          {"spool_lag_s", p.spool_lag_s},
          {"delay_samples", p.delay_samples},
          {"ramp_start_right_v", r.ramp_right_v},
          {"ramp_start_left_v", r.ramp_left_v},
          {"estimation_simulation_pct", r.estimation_pct},
          {"validation_simulation_pct", validated ? nlohmann::json(r.validation_pct) : nlohmann::json(nullptr)}};
}

}  // namespace epa::report
