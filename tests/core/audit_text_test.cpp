// How audit entries read in the log and in `epa tuning audit`: a change with its values, a value
// there was not as "none" (not "nan"), and an interface's event (a refused unlock key, no values)
// as nothing changed (it read "set unlock from 0 to 0").
#include "core/audit.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace epa::core {
namespace {

TEST(AuditText, AChangeAValueThereWasNotAndAnEventReadAsWhatTheyAre) {
  EXPECT_EQ(audit_text({0, "web 127.0.0.1", "mode", 1, 0}), "set mode from 1 to 0");
  EXPECT_EQ(audit_text({0, "web 127.0.0.1", "lc_mm", 5, 2.5}), "set lc_mm from 5 to 2.5");
  EXPECT_EQ(audit_text({0, "cli", "running_tuning_set", NAN, 4}), "set running_tuning_set from none to 4");
  const AuditEntry refused_key{0, "modbus 127.0.0.1:50312", "unlock", NAN, NAN};
  EXPECT_TRUE(is_audit_event(refused_key));
  EXPECT_EQ(audit_text(refused_key), "(unlock: nothing changed)");
  EXPECT_FALSE(is_audit_event({0, "cli", "running_tuning_set", NAN, 4}));
  EXPECT_FALSE(is_audit_event({0, "web", "setpoint_mm", 0, 0}));  // a write of the value it had is a change
}

}  // namespace
}  // namespace epa::core
