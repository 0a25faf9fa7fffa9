#pragma once
// A recorded run file as a row of the store's run history: its controller, the step it made
// (first position to the final reference) and the same step metrics `epa simulate` reports.
#include <string>

#include "core/run.hpp"
#include "store/run_record.hpp"

namespace epa::appliance {

store::RunRecord to_run_record(const std::string& path, const core::Run& run);

}  // namespace epa::appliance
