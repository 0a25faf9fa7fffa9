#include "hal/daq.hpp"

namespace epa::hal {

const char* to_string(IoStatus s) {
  switch (s) {
    case IoStatus::kOk: return "ok";
    case IoStatus::kTimeout: return "timeout";
    case IoStatus::kError: return "error";
  }
  return "?";
}

}  // namespace epa::hal
