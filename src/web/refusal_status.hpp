#pragma once
// The HTTP status a refused command is answered with.
#include "points/gate_result.hpp"

namespace epa::web {

// 400 not writable or invalid, 403 forbidden, 409 not now, 503 busy; 200 when not refused.
int http_status(points::Refusal r);

}  // namespace epa::web
