#include "modbus/refusal_exception.hpp"

#include "modbus/exception_codes.hpp"

namespace epa::modbus {

std::uint8_t exception_code(points::Refusal r) {
  switch (r) {
    case points::Refusal::kNone: return 0;
    case points::Refusal::kNotWritable: return kIllegalAddress;
    case points::Refusal::kInvalidValue: return kIllegalValue;
    case points::Refusal::kForbidden:
    case points::Refusal::kConflict: return kCannotApply;
    case points::Refusal::kBusy: return kServerBusy;
  }
  return kCannotApply;
}

}  // namespace epa::modbus
