#pragma once
// GET /metrics: the snapshot in the Prometheus text exposition format (version 0.0.4), with
// HELP and TYPE lines, for the site's monitoring to scrape.
#include <string>

#include "runtime/snapshot.hpp"
#include "web/json_api.hpp"

namespace epa::web {

std::string prometheus_text(const runtime::Snapshot& s, const ModbusStats& modbus, std::uint64_t web_requests);

}  // namespace epa::web
