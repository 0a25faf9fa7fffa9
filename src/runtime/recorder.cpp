#include "runtime/recorder.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "core/audit.hpp"
#include "core/format.hpp"
#include "core/free_space.hpp"
#include "core/run_file.hpp"
#include "core/utc_stamp.hpp"

namespace epa::runtime {

namespace fs = std::filesystem;

Recorder::Recorder(RecorderConfig config, LoopChannels& channels, Log log, Written written)
    : config_(std::move(config)), ch_(channels), log_(std::move(log)), written_(std::move(written)) {}

Recorder::~Recorder() { stop(); }

void Recorder::start() {
  thread_ = std::thread([this] {
    while (!stop_.load()) {
      process_pending();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
}

void Recorder::stop() {
  if (thread_.joinable()) {
    stop_ = true;
    thread_.join();
  }
  process_pending();
}

std::size_t Recorder::process_pending() {
  std::size_t n = 0;
  RecordRequest r;
  while (ch_.record_requests.try_pop(r)) {
    if (r.reason == RecordRequest::Reason::kMove && !config_.per_move) continue;
    if (may_write(r)) {
      write(r);
      ++n;
    }
    if (r.reason == RecordRequest::Reason::kMove) last_move_end_ = std::max(last_move_end_, r.end);
  }
  return n;
}

bool Recorder::may_write(const RecordRequest& request) {
  auto skip = [&](const std::string& why) {
    ++files_skipped_;
    if (log_) log_("recorder: a run file not written: " + why);
    return false;
  };
  const auto free = core::free_bytes(fs::exists(config_.directory) ? config_.directory : ".");
  if (free && *free < config_.min_free_bytes)
    return skip("the disk has " + std::to_string(*free / (1024 * 1024)) + " MiB free, below the " +
                std::to_string(config_.min_free_bytes / (1024 * 1024)) + " MiB kept for the tuning store");
  if (request.reason != RecordRequest::Reason::kMove) return true;  // the gate paces record requests; experiments are rare
  // A token bucket: a burst of a minute's worth, refilled at the rate.
  const auto now = std::chrono::steady_clock::now();
  const double per_s = config_.move_files_per_minute / 60.0;
  if (tokens_at_ == std::chrono::steady_clock::time_point{}) move_tokens_ = config_.move_files_per_minute;
  else move_tokens_ = std::min(config_.move_files_per_minute, move_tokens_ + std::chrono::duration<double>(now - tokens_at_).count() * per_s);
  tokens_at_ = now;
  if (move_tokens_ < 1.0) return skip("more than " + core::format_number(config_.move_files_per_minute) + " moves a minute");
  move_tokens_ -= 1.0;
  return true;
}

std::string Recorder::last_file() const {
  std::lock_guard lock(last_file_mutex_);
  return last_file_;
}

namespace {

const char* to_string(ExcitationEnd how) {
  switch (how) {
    case ExcitationEnd::kComplete: return "complete";
    case ExcitationEnd::kStopped: return "stopped";
    case ExcitationEnd::kFault: return "fault";
  }
  return "?";
}

// UTC, to the second: an experiment's file is never overwritten by one of a later start.
std::string utc_stamp() { return core::utc_stamp(core::unix_time_ms()); }

}  // namespace

void Recorder::write(const RecordRequest& request) {
  core::Run run;
  run.Ts = config_.Ts;
  // As docs/formats.md says: open-loop when no controller drove the samples, so `epa identify` takes them as
  // open-loop data.
  run.set_meta("controller", request.open_loop ? "open-loop" : std::string(control::to_string(request.controller)));
  run.set_meta("source", config_.source);
  const auto first = ch_.samples.copy_out(request.first, request.end, run);
  if (run.size() == 0) {  // a move cut short in the cycle it began has none; else the loop lapped them
    if (log_ && request.end > request.first) log_("recorder: no samples left to write (the ring was overwritten)");
    return;
  }
  if (request.open_loop) {  // no reference and no controller output: only what the valve got and the piston did
    run.r_mm.clear();
    run.uc_V.clear();
  }
  // Times restart at 0 so the file is a step response from its first sample.
  const double t0 = run.t_s.front();
  for (double& t : run.t_s) t = std::round((t - t0) / config_.Ts) * config_.Ts;

  char name[160];
  if (request.reason == RecordRequest::Reason::kMove) {
    const auto& m = request.move;
    // What core::move_metrics needs to recompute the move's figures from this file alone.
    run.set_meta("move", std::to_string(m.number));
    run.set_meta("from_mm", core::format_exact(m.from_mm));
    run.set_meta("step_mm", core::format_number(m.to_mm - m.from_mm));
    run.set_meta("target_mm", core::format_exact(m.to_mm));
    run.set_meta("move_end", std::string(core::to_string(m.end)));
    run.set_meta("ess_window_s", core::format_number(request.ess_window_s));
    if (first != request.first) run.set_meta("samples_lost", std::to_string(first - request.first));
    std::snprintf(name, sizeof name, "move-%04u-%s-%gto%gmm.csv", m.number,
                  std::string(control::to_string(request.controller)).c_str(), m.from_mm, m.to_mm);
  } else if (request.reason == RecordRequest::Reason::kExcitation) {
    const auto& e = request.excitation;  // the keys `epa excite` writes, and the rest of the settings
    run.set_meta("excitation_seed", std::to_string(e.seed));
    run.set_meta("amplitude_max_V", core::format_number(e.amplitude_max_v));
    run.set_meta("amplitude_min_V", core::format_number(e.amplitude_min_v));
    run.set_meta("duration_s", core::format_number(e.duration_s));
    run.set_meta("guard_mm", core::format_number(e.guard_mm));
    run.set_meta("pulse_signs", e.sweep ? "sweep" : "centring");
    run.set_meta("excitation_end", to_string(request.excitation_end));
    run.set_meta("pulses", std::to_string(request.pulses));
    run.set_meta("pulses_cut", std::to_string(request.pulses_cut));
    if (first != request.first) run.set_meta("samples_lost", std::to_string(first - request.first));
    std::snprintf(name, sizeof name, "excite-%s-%04llu-seed%lu%s.csv", utc_stamp().c_str(),
                  static_cast<unsigned long long>(++excitation_count_), static_cast<unsigned long>(e.seed),
                  request.excitation_end == ExcitationEnd::kComplete ? "" : request.excitation_end == ExcitationEnd::kFault ? "-fault" : "-stopped");
  } else {
    std::snprintf(name, sizeof name, "record-%04llu-sample%llu.csv", static_cast<unsigned long long>(++request_count_),
                  static_cast<unsigned long long>(first));
  }
  std::error_code ec;
  std::filesystem::create_directories(config_.directory, ec);
  if (!quota_) quota_.emplace(config_.directory, config_.quota_bytes, log_);  // the files of earlier runs count
  const std::string path = (std::filesystem::path(config_.directory) / name).string();
  if (auto s = core::write_run_file(path, run); !s) {
    if (log_) log_("recorder: " + s.error().message);
    return;
  }
  {
    std::lock_guard lock(last_file_mutex_);
    last_file_ = path;
  }
  ++files_written_;
  if (log_) log_("recorder: wrote " + path + " (" + std::to_string(run.size()) + " samples)");
  quota_->add(path);
  if (written_) written_(path, run);
  if (move_with_rest_ && request.reason == RecordRequest::Reason::kMove) hand_over_with_rest(request, run);
}

void Recorder::hand_over_with_rest(const RecordRequest& request, const core::Run& move) const {
  const auto rest = static_cast<std::uint64_t>(std::lround(config_.rest_before_s / config_.Ts));
  const std::uint64_t from = std::max(request.first > rest ? request.first - rest : 0, last_move_end_);
  core::Run with_rest;
  with_rest.Ts = config_.Ts;
  with_rest.metadata = move.metadata;
  const auto first = ch_.samples.copy_out(std::min(from, request.first), request.end, with_rest);
  if (with_rest.size() < move.size()) return move_with_rest_(move);  // the ring has lapped the rest meanwhile
  const double t0 = with_rest.t_s.front();
  for (double& t : with_rest.t_s) t = std::round((t - t0) / config_.Ts) * config_.Ts;
  with_rest.set_meta("rest_before_samples", std::to_string(request.first - first));
  move_with_rest_(with_rest);
}

}  // namespace epa::runtime
