#pragma once
// What the status page's server needs of the appliance's commissioning service (app/
// commission_service.*), so the web library does not depend on it: the control every interface
// has (points/commission_control.hpp), and the progress, the last outcome as epa-commission/1 JSON
// and the HTML report.
#include <optional>
#include <string>

#include "points/commission_control.hpp"

namespace epa::web {

class CommissionPort : public points::CommissionControl {
 public:
  // {"running", "stage", "verdict", "percent", "message"}
  virtual std::string status_json() const = 0;
  virtual std::optional<std::string> result_json() const = 0;  // of the last run that ended
  virtual std::optional<std::string> report_html() const = 0;
};

}  // namespace epa::web
