// The catalog itself: one entry per PointId in order, unique names, ranges for writable points;
// and the rule that a point's public name is written once in the source tree, in the catalog.
#include "points/point_catalog.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

#include "runtime/command_rules.hpp"

namespace epa::points {
namespace {

TEST(PointCatalog, OneEntryPerIdInOrderWithUniqueNames) {
  const auto catalog = point_catalog();
  ASSERT_EQ(catalog.size(), kPointCount);
  std::set<std::string_view> names;
  for (std::size_t i = 0; i < catalog.size(); ++i) {
    EXPECT_EQ(index(catalog[i].id), i);
    EXPECT_TRUE(names.insert(catalog[i].name).second) << catalog[i].name;
    EXPECT_NE(catalog[i].read, nullptr) << catalog[i].name;
    EXPECT_EQ(find_point(catalog[i].name), &catalog[i]);
    if (catalog[i].writable()) {
      EXPECT_LE(catalog[i].min, catalog[i].max) << catalog[i].name;
    }
  }
  EXPECT_EQ(find_point("no_such_point"), nullptr);
  EXPECT_EQ(name(PointId::kSetpoint), "setpoint_mm");
  EXPECT_EQ(name(indexed_id(PointId::kG0, 3)), "G3");
}

// Files that spell a point's name as a key of their own documented format (docs/formats.md), not as
// the point: the configuration's [startup] setpoint_mm and [controller] lc_mm, epa-tuning/1 and
// epa-model/1 keys, the run files' `controller` metadata, report labels, the recent-moves list.
const std::map<std::string, std::string> kFormatFiles = {
    {"config/appliance_config.cpp", "epa-config/1 keys"},
    {"store/tuning_file.cpp", "epa-tuning/1 keys"},
    {"core/dead_zone.hpp", "epa-model/1 and epa-tuning/1 dead-zone keys"},
    {"core/model_file.cpp", "epa-model/1 keys"},
    {"core/run_file.cpp", "epa-run/1 metadata"},
    {"core/move_metrics.cpp", "epa-run/1 metadata: a move's move_end values, which name how it ended, not the status bits"},
    {"runtime/recorder.cpp", "epa-run/1 metadata"},
    {"diag/model_health.cpp", "the health states' names (hunting: the law hunted), not the status bit"},
    {"points/health_control.hpp", "the health states' names as the interfaces give them, not the status bit"},
    {"appliance/health_monitor.cpp", "epa-run/1 metadata: which recorded runs are moves the monitor judges"},
    {"appliance/run_history.cpp", "epa-run/1 metadata"},
    {"app/identify_command.cpp", "epa-run/1 metadata"},
    {"app/simulate_command.cpp", "epa-run/1 metadata"},
    {"ident/excitation.cpp", "epa-run/1 metadata"},
    {"sim/closed_loop.cpp", "epa-run/1 metadata"},
    {"report/identify_report.cpp", "a report's row labels"},
    {"commission/commission_spec.cpp", "the commissioning spec's keys"},
    {"commission/commission_sequence.cpp", "epa-commission/1 keys"},
    {"app/tuning_command.cpp", "epa tuning show's labels"},
    {"app/faults_command.cpp", "the subcommand's own name, `epa faults`"},
    {"web/json_api.hpp", "/api/records' keys (RecordKeys)"},
    {"web/json_api.cpp", "the loop statistics' cycle count, the recent-moves list and the fault history, other values than the points"},
};

// An HMI decodes last_command_refusal from its description: every refusal the loop can give is
// named there (codes 11-13 were missing once, when they were added to the loop only).
TEST(PointCatalog, LastCommandRefusalNamesEveryRefusal) {
  const std::string text(point(PointId::kLastCommandRefusal).description);
  int code = 1;
  for (; runtime::describe(static_cast<runtime::CommandRefusal>(code)) != "unknown"; ++code)
    EXPECT_NE(text.find(std::to_string(code) + " "), std::string::npos) << "refusal " << code << " (" << runtime::describe(static_cast<runtime::CommandRefusal>(code)) << ")";
  EXPECT_GE(code, 14);
  EXPECT_EQ(text.find(std::to_string(code) + " "), std::string::npos) << "names a refusal the loop does not have";
}

TEST(PointCatalog, APointsNameIsWrittenOnceInTheSourceTreeInTheCatalog) {
  std::set<std::string> names;
  for (const auto& p : point_catalog()) names.insert(std::string(p.name));
  const std::filesystem::path src = std::filesystem::path(EPA_SOURCE_DIR) / "src";
  const std::regex literal("\"([A-Za-z_0-9]+)\"");
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(src)) {
    if (!entry.is_regular_file()) continue;
    const std::string rel = std::filesystem::relative(entry.path(), src).generic_string();
    if (rel == "points/point_catalog.cpp" || kFormatFiles.contains(rel)) continue;
    ++files;
    std::ifstream in(entry.path());
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      const auto code = line.substr(0, line.find("//"));  // comments may show examples
      for (std::sregex_iterator it(code.begin(), code.end(), literal), end; it != end; ++it)
        EXPECT_FALSE(names.contains((*it)[1].str()))
            << "src/" << rel << ":" << n << " spells the point name \"" << (*it)[1].str()
            << "\": use points::name(PointId::...) (or, for a file format's own key, list the file here)";
    }
  }
  EXPECT_GT(files, 100);
}

}  // namespace
}  // namespace epa::points
