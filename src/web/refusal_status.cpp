#include "web/refusal_status.hpp"

namespace epa::web {

int http_status(points::Refusal r) {
  switch (r) {
    case points::Refusal::kNone: return 200;
    case points::Refusal::kNotWritable:
    case points::Refusal::kInvalidValue: return 400;
    case points::Refusal::kForbidden: return 403;
    case points::Refusal::kConflict: return 409;
    case points::Refusal::kBusy: return 503;
  }
  return 400;
}

}  // namespace epa::web
