#include "appliance/commissioning_service.hpp"

#include <nlohmann/json.hpp>

#include "commission/commission_spec.hpp"

namespace epa::appliance {

CommissioningService::CommissioningService(AxisFactory make_axis, commission::Identify identify, RenderReport render_report,
                                           commission::ApplianceBounds bounds, Log log, core::AuditSink* audit)
    : make_axis_(std::move(make_axis)),
      identify_(std::move(identify)),
      render_report_(std::move(render_report)),
      bounds_(std::move(bounds)),
      log_(std::move(log)),
      audit_(audit) {}

void CommissioningService::audit(const std::string& source, double command) const {
  if (audit_) audit_->record({{core::unix_time_ms(), source, std::string(points::name(points::PointId::kCommissionCommand)), 0.0, command}});
}

CommissioningService::~CommissioningService() {
  {
    std::lock_guard lock(mutex_);
    if (sequence_) sequence_->abort();
  }
  if (thread_.joinable()) thread_.join();
}

points::CommissionStartResult CommissioningService::start(const std::string& spec_json, const std::string& source) {
  auto spec = spec_json.find_first_not_of(" \t\r\n") == std::string::npos ? core::Result<commission::CommissionSpec>(commission::CommissionSpec{})
                                                                          : commission::parse_commission_spec(spec_json);
  if (!spec) return {points::CommissionStart::kBadSpec, spec.error().message};
  if (auto s = commission::check_runnable(*spec, bounds_); !s) return {points::CommissionStart::kBadSpec, s.error().message};
  std::lock_guard lock(mutex_);
  if (running_) return {points::CommissionStart::kBusy, "a commissioning run is under way: " + sequence_->progress().message};
  if (thread_.joinable()) thread_.join();  // the last run's thread has ended (running_ is false)
  axis_ = make_axis_("commission (" + source + ")");
  sequence_ = std::make_unique<commission::CommissionSequence>(*axis_, identify_, log_);
  running_ = true;
  if (log_) log_("commission: started by " + source + " with spec " + commission::format_commission_spec(*spec));
  audit(source, 1.0);
  thread_ = std::thread([this, s = *spec] {
    const auto outcome = sequence_->run(s);
    auto json = commission::format_commission_json(outcome);
    auto html = render_report_(outcome);
    std::lock_guard done(mutex_);
    result_json_ = std::move(json);
    report_html_ = std::move(html);
    last_progress_ = sequence_->progress();
    running_ = false;
  });
  return {};
}

bool CommissioningService::abort(const std::string& source) {
  std::lock_guard lock(mutex_);
  if (!running_) return false;
  if (log_) log_("commission: abort requested by " + source);
  audit(source, 2.0);  // under the one who aborts: what the run does next stays under its starter
  sequence_->abort();
  return true;
}

bool CommissioningService::running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

commission::Progress CommissioningService::progress() const {
  std::lock_guard lock(mutex_);
  return running_ ? sequence_->progress() : last_progress_;
}

points::CommissionView CommissioningService::view() const {
  std::lock_guard lock(mutex_);
  const auto p = running_ ? sequence_->progress() : last_progress_;
  return {true, running_, static_cast<int>(p.stage), static_cast<int>(p.verdict), p.percent};
}

std::string CommissioningService::status_json() const {
  bool is_running;
  commission::Progress p;
  {
    std::lock_guard lock(mutex_);
    is_running = running_;
    p = running_ ? sequence_->progress() : last_progress_;
  }
  const nlohmann::json j = {{"running", is_running},
                            {"stage", std::string(commission::to_string(p.stage))},
                            {"verdict", std::string(commission::to_string(p.verdict))},
                            {"percent", p.percent},
                            {"message", p.message}};
  return j.dump();
}

std::optional<std::string> CommissioningService::result_json() const {
  std::lock_guard lock(mutex_);
  return result_json_;
}

std::optional<std::string> CommissioningService::report_html() const {
  std::lock_guard lock(mutex_);
  return report_html_;
}

}  // namespace epa::appliance
