#include "ident/output_error_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"
#include "ident/arx_metrics.hpp"
#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

using testdata::kNoiseFreeTol;
using testdata::kEq9;
using testdata::kPaperDz;
using testdata::max_abs_diff;

ArxModel paper_arx() {
  const auto m = core::paper::model();
  ArxModel a;
  a.orders = kEq9;
  for (std::size_t i = 1; i < m.A.size(); ++i) a.a.push_back(m.A[i]);
  for (std::size_t j = 1; j < m.B.size(); ++j) a.b.push_back(m.B[j]);
  return a;
}

// The paper's model with every parameter moved by a few per cent: a start the fit must walk back.
ArxModel perturbed_arx() {
  ArxModel a = paper_arx();
  a.a[0] *= 1.02, a.a[1] *= 0.97;
  for (double& b : a.b) b *= 1.05;
  return a;
}

const std::vector<Segment>& noise_free() {
  static const auto s = testdata::paper_segments(3, 40.0, 0.0);
  return s;
}

TEST(OutputErrorFit, NoiseFreeDataGiveEq9And10FromAPerturbedStart) {
  const core::DeadZone start{.m_r = 1.5, .m_l = 1.0, .b_r = 1.15, .b_l = -1.8};
  auto fit = fit_output_error(noise_free(), perturbed_arx(), start, {});
  ASSERT_TRUE(fit.has_value()) << fit.error().message;
  EXPECT_LT(fit->loss, 1e-12);
  EXPECT_GT(fit->start_loss, 1e3 * 1e-12);
  // Unit normalisation: compare the products m B.
  const double m_l = kPaperDz.m_l;
  ArxModel scaled = fit->model;
  for (double& b : scaled.b) b /= m_l;
  EXPECT_LT(max_abs_diff(scaled.A(), core::paper::model().A), kNoiseFreeTol);
  EXPECT_LT(max_abs_diff(scaled.B(), core::paper::model().B), kNoiseFreeTol);
  EXPECT_NEAR(fit->dead_zone.b_r, kPaperDz.b_r, kNoiseFreeTol);
  EXPECT_NEAR(fit->dead_zone.b_l, kPaperDz.b_l, kNoiseFreeTol);
  EXPECT_NEAR(fit->dead_zone.m_r / fit->dead_zone.m_l, kPaperDz.m_r / kPaperDz.m_l, kNoiseFreeTol);
  EXPECT_DOUBLE_EQ(fit->dead_zone.m_l, 1.0);
}

TEST(OutputErrorFit, AnIntegratingModelKeepsItsPoleAtOneExactly) {
  ArxModel start = perturbed_arx();
  start.a[2] += 0.01;  // A(1) = 0.01: the start does not integrate
  auto fit = fit_output_error(noise_free(), start, {.m_r = 1.6, .m_l = 1.0, .b_r = 1.2, .b_l = -1.7}, {});
  ASSERT_TRUE(fit.has_value()) << fit.error().message;
  EXPECT_NEAR(fit->model.A().at(1.0), 0.0, 1e-14);
  OutputErrorOptions free_poles;
  free_poles.integrating = false;
  auto loose = fit_output_error(noise_free(), start, {.m_r = 1.6, .m_l = 1.0, .b_r = 1.2, .b_l = -1.7}, free_poles);
  ASSERT_TRUE(loose.has_value()) << loose.error().message;
  EXPECT_NE(loose->model.A().at(1.0), 0.0);  // free coefficients land near, not on, z = 1
}

TEST(OutputErrorFit, BreakPointsAndPolesStayWithinTheirBounds) {
  OutputErrorOptions o;
  o.right = {1.3, 1.4};    // excludes eq 10's 1.232
  o.left = {-1.6, -1.5};   // excludes -1.722
  o.slowest_mode_s = 0.01;  // |z| <= 0.61: excludes the paper's -0.768
  auto fit = fit_output_error(noise_free(), paper_arx(), {.m_r = 1.65, .m_l = 1.0, .b_r = 1.232, .b_l = -1.722}, o);
  ASSERT_TRUE(fit.has_value()) << fit.error().message;
  EXPECT_GE(fit->dead_zone.b_r, 1.3);
  EXPECT_LE(fit->dead_zone.b_r, 1.4);
  EXPECT_GE(fit->dead_zone.b_l, -1.6);
  EXPECT_LE(fit->dead_zone.b_l, -1.5);
  // The roots of A other than z = 1.
  double radius = 0.0;
  for (const auto& z : fit->model.A().z_roots())
    if (std::abs(z - 1.0) > 1e-9) radius = std::max(radius, std::abs(z));
  EXPECT_LE(radius, std::exp(-0.005 / 0.01) + 1e-12);
  EXPECT_GT(fit->loss, 1e-6);  // the bounds cost fit on data from eq 9-10
}

TEST(OutputErrorFit, TheLossIsTheFreeRunErrorOfWholeSegments) {
  const auto& data = noise_free();
  const auto m = paper_arx();
  core::DeadZone dz = kPaperDz;
  dz.m_r /= dz.m_l, dz.m_l = 1.0;
  ArxModel unit = m;
  for (double& b : unit.b) b *= kPaperDz.m_l;
  EXPECT_LT(windowed_simulation_loss(data, unit, dz, 0), 1e-20);
  // A wrong gain integrates into a growing error; short windows restart it from the measured y.
  for (double& b : unit.b) b *= 1.01;
  const double whole = windowed_simulation_loss(data, unit, dz, 0), windowed = windowed_simulation_loss(data, unit, dz, 200);
  EXPECT_GT(whole, 10.0 * windowed);
  EXPECT_GT(windowed, 0.0);
}

TEST(OutputErrorFit, OptionsAndStartsAreChecked) {
  const core::DeadZone dz{.m_r = 1.6, .m_l = 1.0, .b_r = 1.2, .b_l = -1.7};
  OutputErrorOptions o;
  o.window_s = -1.0;
  auto r = fit_output_error(noise_free(), paper_arx(), dz, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("window"), std::string::npos) << r.error().message;
  o = {};
  o.right = {1.5, 1.4};
  r = fit_output_error(noise_free(), paper_arx(), dz, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("b_r"), std::string::npos) << r.error().message;
  o = {};
  o.window_s = 0.01;  // 2 samples: shorter than the model's memory
  r = fit_output_error(noise_free(), paper_arx(), dz, o);
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("too short"), std::string::npos) << r.error().message;
  ArxModel none = paper_arx();
  none.orders.na = 0, none.a.clear();
  r = fit_output_error(noise_free(), none, dz, {});
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("na >= 1"), std::string::npos) << r.error().message;
}

TEST(OutputErrorFit, TheSameDataGiveTheSameModel) {
  const auto noisy = testdata::paper_segments(1, 30.0, 0.1);
  const core::DeadZone start{.m_r = 1.5, .m_l = 1.0, .b_r = 1.15, .b_l = -1.8};
  auto a = fit_output_error(noisy, perturbed_arx(), start, {});
  auto b = fit_output_error(noisy, perturbed_arx(), start, {});
  ASSERT_TRUE(a.has_value() && b.has_value());
  EXPECT_EQ(a->model.a, b->model.a);
  EXPECT_EQ(a->model.b, b->model.b);
  EXPECT_EQ(a->dead_zone, b->dead_zone);
  EXPECT_EQ(a->evaluations, b->evaluations);
}

}  // namespace
}  // namespace epa::ident
