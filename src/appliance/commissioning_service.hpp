#pragma once
// The appliance's commissioning service: one commissioning sequence at a time on its own thread,
// off the scan cycle; started and aborted from the page (token), Modbus (unlocked) or `epa
// commission` (over HTTP); its progress, last outcome (epa-commission/1) and report for all three.
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "commission/axis.hpp"
#include "core/audit.hpp"
#include "commission/commission_sequence.hpp"
#include "commission/commission_spec.hpp"
#include "web/commission_port.hpp"

namespace epa::appliance {

class CommissioningService final : public web::CommissionPort {
 public:
  using Log = std::function<void(const std::string&)>;
  // The axis for a run started by `source` (its commands are audited as coming from it).
  using AxisFactory = std::function<std::unique_ptr<commission::Axis>(const std::string& source)>;
  // The HTML report of an outcome: drawn by the caller's report writer, so this service knows no charts.
  using RenderReport = std::function<std::string(const commission::CommissionOutcome&)>;

  // `bounds`: what this appliance can run; a spec beyond them is refused before the axis is touched.
  // `audit`: where a start and an abort are audited, each under the source that asked for it,
  // whichever interface it came through.
  CommissioningService(AxisFactory make_axis, commission::Identify identify, RenderReport render_report,
                       commission::ApplianceBounds bounds, Log log, core::AuditSink* audit = nullptr);
  ~CommissioningService() override;  // aborts a run under way and waits for it (the valve safe)
  CommissioningService(const CommissioningService&) = delete;
  CommissioningService& operator=(const CommissioningService&) = delete;

  points::CommissionStartResult start(const std::string& spec_json, const std::string& source) override;
  bool abort(const std::string& source) override;
  points::CommissionView view() const override;
  std::string status_json() const override;
  std::optional<std::string> result_json() const override;
  std::optional<std::string> report_html() const override;

  bool running() const;
  commission::Progress progress() const;

 private:
  AxisFactory make_axis_;
  commission::Identify identify_;
  RenderReport render_report_;
  commission::ApplianceBounds bounds_;
  Log log_;
  core::AuditSink* audit_;
  void audit(const std::string& source, double command) const;  // commission_command: 1 start, 2 abort
  mutable std::mutex mutex_;
  std::unique_ptr<commission::Axis> axis_;
  std::unique_ptr<commission::CommissionSequence> sequence_;
  std::thread thread_;
  bool running_ = false;
  std::optional<std::string> result_json_, report_html_;
  commission::Progress last_progress_;
};

}  // namespace epa::appliance
