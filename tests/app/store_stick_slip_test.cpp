// The stick-slip model in the tuning store as the appliance and `epa tuning` use it, in-process: the
// store seeded from the configuration's model file keeps the file's stick-slip model, and `epa tuning
// show` says whether a set's model has one.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <sstream>

#include "../support/temp_path.hpp"
#include "app/tuning_command.hpp"
#include "appliance/store_setup.hpp"
#include "core/paper_reference.hpp"
#include "store/model_table.hpp"
#include "store/store_file.hpp"

namespace epa::app {
namespace {

// A model file as `epa identify --validate --out` writes it for a stick-slip axis.
core::ModelFile identified_stick_slip_file() {
  core::StickSlipParams params;
  params.coulomb_mm = 4.5, params.static_mm = 6.75, params.delay_samples = 2;
  return {.model = core::paper::model(), .source = "epa identify: na=3 nb=3 nk=1 from a.csv", .stick_slip = params,
          .axis_model = core::AxisModel::kStickSlip, .identified_drive_v = std::array<double, 2>{-3.0, 2.5},
          .stick_slip_spread = core::StickSlipSpread{.friction_log_ratio = 0.33, .flow_gain_log_ratio = 0.08, .break_v = 0.11,
                                                     .spool_lag_s = 0.012, .delay_samples = 1.0}};
}

store::StoreSeed seed_of(const core::ModelFile& file) {
  const appliance::ControllerPolynomials paper{core::paper::F(), core::paper::G(), core::paper::G(), "paper eq 12-13"};
  return appliance::make_seed("initial", file, paper, control::ControllerKind::kPpFfidz, core::paper::kLcDefaultMm,
                              core::paper::kValveLimitV);
}

// `epa tuning --db <db> show <set>`, parsed and run as main() does; its standard output.
std::string tuning_show(const std::string& db, const std::string& set) {
  CLI::App cli;
  TuningOptions o;
  add_tuning_command(cli, o);
  cli.parse("tuning --db " + db + " show " + set, false);
  std::ostringstream out, err;
  EXPECT_EQ(run_tuning(cli, o, out, err), 0) << err.str();
  return out.str();
}

TEST(StoreStickSlip, TheSeedFromAModelFileCarriesItsStickSlipModel) {
  const core::ModelFile file = identified_stick_slip_file();
  const store::StoreSeed seed = seed_of(file);
  EXPECT_EQ(seed.model.name, "initial");
  EXPECT_EQ(seed.model.source, file.source);
  EXPECT_EQ(seed.model.axis_model, core::AxisModel::kStickSlip);
  EXPECT_EQ(seed.model.stick_slip, file.stick_slip);
  EXPECT_EQ(seed.model.stick_slip_spread, file.stick_slip_spread);
  EXPECT_EQ(seed.model.identified_drive_v, file.identified_drive_v);

  // And the store created from it keeps them.
  const epa::test::TempDir dir("seed");
  auto opened = store::open_store((dir.path / "epa.db").string(), seed, 1000);
  ASSERT_TRUE(opened) << opened.error().message;
  ASSERT_TRUE(opened->seeded);
  auto model = store::ModelTable(opened->db).get(1);
  ASSERT_TRUE(model) << model.error().message;
  EXPECT_EQ(model->stick_slip, file.stick_slip);
  EXPECT_EQ(model->stick_slip_spread, file.stick_slip_spread);
  EXPECT_EQ(model->identified_drive_v, file.identified_drive_v);
  EXPECT_EQ(model->axis_model, core::AxisModel::kStickSlip);

  // A model file without one (the paper's) seeds a model without one.
  const store::StoreSeed paper = seed_of({core::paper::model(), ""});
  EXPECT_FALSE(paper.model.stick_slip);
  EXPECT_EQ(paper.model.source, "the configuration's model");
}

TEST(StoreStickSlip, TuningShowSaysWhetherTheSetsModelHasOne) {
  const epa::test::TempDir dir("show");
  const std::string db = (dir.path / "epa.db").string();
  {
    auto opened = store::open_store(db, seed_of(identified_stick_slip_file()), 1000);
    ASSERT_TRUE(opened) << opened.error().message;
  }
  const std::string sticky = tuning_show(db, "initial");
  EXPECT_NE(sticky.find("\n  stick-slip model: yes (axis_model stick-slip)\n"), std::string::npos) << sticky;

  const epa::test::TempDir plain_dir("show-plain");
  const std::string plain_db = (plain_dir.path / "epa.db").string();
  {
    auto opened = store::open_store(plain_db, seed_of({core::paper::model(), "paper eq 9-10"}), 1000);
    ASSERT_TRUE(opened) << opened.error().message;
  }
  const std::string plain = tuning_show(plain_db, "initial");
  EXPECT_NE(plain.find("\n  stick-slip model: none\n"), std::string::npos) << plain;
  EXPECT_NE(plain.find("\n  model mm_per_volt: 50\n  stick-slip model: none\n  model fit: {}\n"), std::string::npos)
      << "one line, between the model's scale and its fit:\n" << plain;
}

}  // namespace
}  // namespace epa::app
