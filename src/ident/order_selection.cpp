#include "ident/order_selection.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace epa::ident {

namespace {

std::optional<int> parse_int(std::string_view s) {
  int v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::string fit_text(double pct) {
  char buf[32];
  if (pct < -999.0) return "  <-999";
  std::snprintf(buf, sizeof buf, "%7.2f", pct);
  return buf;
}

}  // namespace

core::Result<OrderRange> parse_order_range(const std::string& text, const std::string& option) {
  const auto colon = text.find(':');
  const auto lo = parse_int(std::string_view(text).substr(0, colon));
  const auto hi = colon == std::string::npos ? lo : parse_int(std::string_view(text).substr(colon + 1));
  if (!lo || !hi)
    return core::invalid_argument(option + " '" + text + "': expected an order like 3 or a range like 1:4");
  if (*lo > *hi) return core::invalid_argument(option + " '" + text + "': the range is empty (" + std::to_string(*lo) +
                                               " > " + std::to_string(*hi) + ")");
  return OrderRange{*lo, *hi};
}

double pole_zero_distance(const ArxModel& m) {
  const auto poles = m.A().z_roots();
  // B = q^-nk (b_1 + ... ): its roots in z, without the nk roots at z = 0 the delay adds.
  const auto zeros = core::Polynomial(m.b).z_roots();
  double d = INFINITY;
  for (const auto& p : poles)
    for (const auto& z : zeros) d = std::min(d, std::abs(p - z));
  return d;
}

std::size_t common_first_row(const OrderSearch& s) {
  return ArxOrders{.na = s.na.hi, .nb = s.nb.hi, .nk = s.nk.hi}.first_row();
}

core::Result<OrderSelection> select_order(const std::vector<Segment>& est, const std::vector<Segment>& val,
                                          const OrderSearch& search) {
  OrderSelection sel;
  sel.first = common_first_row(search);
  const bool validating = !val.empty();
  for (int nk = search.nk.lo; nk <= search.nk.hi; ++nk)
    for (int na = search.na.lo; na <= search.na.hi; ++na)
      for (int nb = search.nb.lo; nb <= search.nb.hi; ++nb) {
        const ArxOrders orders{.na = na, .nb = nb, .nk = nk};
        if (auto s = orders.validate(); !s) return core::invalid_argument("order search: " + s.error().message);
        auto e = estimate_arx(est, orders, sel.first);
        if (!e) {
          sel.skipped.push_back(orders.to_string() + ": " +
                                (e.error().code == core::ErrorCode::kNumerical
                                     ? "rank-deficient regression (more parameters than these data determine)"
                                     : e.error().message));
          continue;
        }
        OrderCandidate c;
        c.estimate = std::move(*e);
        c.estimation = fit_percent(c.estimate.model, est, sel.first);
        if (validating) c.validation = fit_percent(c.estimate.model, val, sel.first);
        c.criteria = information_criteria(c.estimate.loss, c.estimate.N, orders.d());
        c.score_pct = validating ? c.validation->simulation_pct : c.estimation.simulation_pct;
        c.pole_zero_distance = pole_zero_distance(c.estimate.model);
        c.cancels = c.pole_zero_distance < search.cancellation_distance;
        sel.candidates.push_back(std::move(c));
      }
  if (auto s = apply_order_rule(sel, search, validating); !s) return s.error();
  return sel;
}

core::Status apply_order_rule(OrderSelection& sel, const OrderSearch& search, bool validating) {
  if (sel.candidates.empty())
    return core::numerical_error("no ARX order in the search could be estimated; first reason: " +
                                 (sel.skipped.empty() ? std::string("empty search") : sel.skipped.front()));

  auto& cs = sel.candidates;
  const bool all_cancel = std::all_of(cs.begin(), cs.end(), [](const OrderCandidate& c) { return c.cancels; });
  if (all_cancel)
    for (auto& c : cs) c.cancels = false;
  std::optional<std::size_t> best_i;
  for (std::size_t i = 0; i < cs.size(); ++i)
    if (!cs[i].cancels && (!best_i || cs[i].score_pct > cs[*best_i].score_pct)) best_i = i;
  sel.best = *best_i;
  const double best = cs[sel.best].score_pct;
  std::optional<std::size_t> pick;
  for (std::size_t i = 0; i < cs.size(); ++i) {
    if (cs[i].cancels || !(cs[i].score_pct >= best - search.tolerance_pct)) continue;
    if (!pick) { pick = i; continue; }
    const auto& c = cs[i];
    const auto& p = cs[*pick];
    const int dc = c.estimate.model.orders.d(), dp = p.estimate.model.orders.d();
    if (dc < dp || (dc == dp && c.criteria.aic < p.criteria.aic)) pick = i;
  }
  sel.recommended = *pick;

  const auto& r = cs[sel.recommended];
  const auto set_aside = std::count_if(cs.begin(), cs.end(), [](const OrderCandidate& c) { return c.cancels; });
  char buf[900];
  const char* on = validating ? "validation" : "estimation";
  std::snprintf(buf, sizeof buf,
                "%s: %s free-run fit %.2f %% (best %.2f %%, %s). Rule: the fewest parameters (here d = na + nb = %d) "
                "among the orders within %.2g fit points of the best, the lowest AIC among equally small ones; "
                "%d order(s) with a pole and a zero closer than %.2g (marked 'cancels') were set aside as "
                "over-parameterised.%s",
                r.estimate.model.orders.to_string().c_str(), on, r.score_pct, best,
                cs[sel.best].estimate.model.orders.to_string().c_str(), r.estimate.model.orders.d(), search.tolerance_pct,
                static_cast<int>(set_aside), search.cancellation_distance,
                validating ? "" : " No validation run was given: a larger model always fits its own data better, so "
                                  "give --validate for an honest choice.");
  sel.reason = buf;
  return core::ok();
}

std::string format_order_table(const OrderSelection& sel) {
  std::string t =
      " na nb nk  d |  estimation fit %  |  validation fit % |   loss V      FPE         AIC     |p-z|min\n"
      "             |  1-step  free-run  |  1-step  free-run |\n";
  char buf[256];
  for (std::size_t i = 0; i < sel.candidates.size(); ++i) {
    const auto& c = sel.candidates[i];
    const auto& o = c.estimate.model.orders;
    const std::string v1 = c.validation ? fit_text(c.validation->one_step_pct) : "      -";
    const std::string v2 = c.validation ? fit_text(c.validation->simulation_pct) : "      -";
    char distance[16] = "      -";
    if (std::isfinite(c.pole_zero_distance)) std::snprintf(distance, sizeof distance, "%7.4f", c.pole_zero_distance);
    std::snprintf(buf, sizeof buf, "%3d%3d%3d%3d | %s  %s   | %s  %s  | %9.3e  %9.3e  %11.4g  %s %s\n", o.na, o.nb,
                  o.nk, o.d(), fit_text(c.estimation.one_step_pct).c_str(), fit_text(c.estimation.simulation_pct).c_str(),
                  v1.c_str(), v2.c_str(), c.criteria.loss, c.criteria.fpe, c.criteria.aic, distance,
                  i == sel.recommended ? "<- recommended" : i == sel.best ? "<- best fit" : c.cancels ? "cancels" : "");
    t += buf;
  }
  for (const auto& s : sel.skipped) t += "  skipped " + s + "\n";
  return t;
}

}  // namespace epa::ident
