#pragma once
// GET /metrics: the snapshot in the Prometheus text exposition format (version 0.0.4), for the
// site's monitoring to scrape, as `promtool check metrics` wants it: every metric with HELP and
// TYPE, base units in the name (meters, volts, seconds: position_mm is epa_position_meters),
// counters ending in _total. A point's metric takes its value and help from the catalog, so
// /metrics, Modbus and /api/status say the same thing; epa_build_info{version="..."} names the version.
#include <string>

#include "points/health_control.hpp"
#include "runtime/snapshot.hpp"
#include "web/json_api.hpp"

namespace epa::web {

// `health`: the model-health monitor's verdict (its points: state, effect, ratio, moves).
std::string prometheus_text(const runtime::Snapshot& s, const ModbusStats& modbus, std::uint64_t web_requests,
                            const points::HealthView& health = {});

}  // namespace epa::web
