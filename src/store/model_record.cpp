#include "store/model_record.hpp"

#include <utility>

namespace epa::store {

core::ModelFile model_file_of(const ModelRecord& r) {
  return {.model = r.model, .source = r.source, .stick_slip = r.stick_slip, .axis_model = r.axis_model,
          .identified_drive_v = r.identified_drive_v, .stick_slip_spread = r.stick_slip_spread};
}

ModelRecord model_record_of(const core::ModelFile& file, std::string name, std::string fit_json) {
  return {.id = 0, .name = std::move(name), .created_ms = 0, .source = file.source, .model = file.model,
          .fit_json = std::move(fit_json), .axis_model = file.axis_model, .identified_drive_v = file.identified_drive_v,
          .stick_slip = file.stick_slip, .stick_slip_spread = file.stick_slip_spread};
}

}  // namespace epa::store
