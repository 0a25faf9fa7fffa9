#include "app/commission_command.hpp"

#include <httplib.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <thread>

#include "app/appliance_http.hpp"
#include "app/cli_checks.hpp"
#include "app/output_file.hpp"
#include "commission/commission_spec.hpp"
#include "core/text_file.hpp"

namespace epa::app {

void add_commission_command(CLI::App& app, CommissionOptions& o) {
  auto* cmd = app.add_subcommand("commission",
                                 "Commission the axis of a running appliance: excite, identify, design, verify in simulation, "
                                 "deploy, verify on the axis, keep or roll back");
  cmd->add_option("--url", o.url, "The appliance's status page, http://HOST:PORT")->capture_default_str();
  cmd->add_option("--token", o.token, "The appliance's [web] token (commands and tuning need it); shows in ps: prefer EPA_TOKEN "
                                      "or --token-file")->envname("EPA_TOKEN");
  cmd->add_option("--token-file", o.token_file, "A file whose first line is the appliance's [web] token");
  cmd->add_option("--spec", o.spec_path, "Commissioning spec (JSON: experiment, design, verification limits); default: built in")
      ->check(CLI::ExistingFile);
  cmd->add_option("--json", o.json_path, "Write the outcome here (epa-commission/1 JSON)");
  cmd->add_option("--report", o.report_path, "Write the report here (HTML)");
  cmd->add_option("--poll", o.poll_s, "Seconds between progress polls")->capture_default_str()->check(CLI::Range(0.05, 60.0));
  cmd->add_option("--timeout", o.timeout_s, "Give up waiting (and abort) after this many seconds")->capture_default_str()
      ->check(cli::kPositive);
}

namespace {

volatile std::sig_atomic_t interrupted = 0;
extern "C" void on_interrupt(int) { interrupted = 1; }

std::string progress_bar(double percent) {
  const int width = 30, filled = static_cast<int>(std::clamp(percent, 0.0, 100.0) / 100.0 * width + 0.5);
  return "[" + std::string(static_cast<std::size_t>(filled), '#') + std::string(static_cast<std::size_t>(width - filled), '.') + "]";
}

}  // namespace

int run_commission(const CommissionOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&err](const std::string& m) { return err << "epa commission: " << m << "\n", 1; };
  std::string spec;
  if (!o.spec_path.empty()) {
    auto text = core::read_text_file(o.spec_path, "commission spec", core::kSmallFileCapBytes);
    if (!text) return fail(text.error().message);
    // Read here first, so that a file that is no spec is named as the file; the appliance checks
    // the values against its own limits.
    if (auto parsed = commission::parse_commission_spec(*text); !parsed) return fail(o.spec_path + ": " + parsed.error().message);
    spec = *text;
  }
  auto token = appliance_token(o.token, o.token_file);
  if (!token) return fail(token.error().message);
  auto made = appliance_client(o.url);
  if (!made) return fail(made.error().message);
  httplib::Client& client = **made;
  const httplib::Headers auth = bearer(*token);

  auto started = client.Post("/api/commission", auth, spec, "application/json");
  if (!started || started->status != 202) return fail("the appliance did not start the commissioning: " + http_failure(started, o.url));
  out << "commissioning started on " << o.url << (o.spec_path.empty() ? " with the default spec" : " with " + o.spec_path) << "\n";

  auto* previous = std::signal(SIGINT, on_interrupt);
  const auto t0 = std::chrono::steady_clock::now();
  bool abort_sent = false;
  std::string last_line;
  nlohmann::json status;
  for (;;) {
    std::this_thread::sleep_for(std::chrono::duration<double>(o.poll_s));
    const bool late = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > o.timeout_s;
    if ((interrupted || late) && !abort_sent) {
      err << "\n" << (late ? "timeout" : "interrupted") << ": aborting the commissioning run\n";
      auto a = client.Post("/api/commission/abort", auth, "", "application/json");
      if (!a || a->status != 200) err << "abort: " << http_failure(a, o.url) << "\n";
      abort_sent = true;
    }
    auto r = client.Get("/api/commission");
    if (!r || r->status != 200) {
      std::signal(SIGINT, previous);
      return fail("progress: " + http_failure(r, o.url));
    }
    status = nlohmann::json::parse(r->body, nullptr, false);
    if (!status.is_object()) continue;
    char line[256];
    std::snprintf(line, sizeof line, "%s %3.0f%% %s", progress_bar(status.value("percent", 0.0)).c_str(), status.value("percent", 0.0),
                  status.value("message", std::string()).c_str());
    if (line != last_line) err << "\r" << line << "\x1b[K" << std::flush, last_line = line;
    if (!status.value("running", true)) break;
  }
  std::signal(SIGINT, previous);
  err << "\n";

  auto result = client.Get("/api/commission/result");
  if (!result || result->status != 200) return fail("the outcome: " + http_failure(result, o.url));
  const auto outcome = nlohmann::json::parse(result->body, nullptr, false);
  if (!outcome.is_object()) return fail("the outcome is not JSON");
  if (!o.json_path.empty())
    if (auto s = write_output(o.json_path, result->body, out); !s) return fail(s.error().message);
  if (!o.report_path.empty()) {
    auto report = client.Get("/api/commission/report");
    if (!report || report->status != 200) return fail("the report: " + http_failure(report, o.url));
    if (auto s = write_output(o.report_path, report->body, out); !s) return fail(s.error().message);
  }
  const std::string verdict = outcome.value("verdict", std::string());
  out << "verdict: " << verdict << ": " << outcome.value("reason", std::string()) << "\n";
  for (const auto& m : outcome.value("verification", nlohmann::json::array())) {
    char buf[200];
    auto num = [&m](const char* k) { return m.contains(k) && m[k].is_number() ? m[k].get<double>() : NAN; };
    std::snprintf(buf, sizeof buf, "  move %6.1f -> %6.1f mm: rise %.3f s, settling %.3f s, e_ss %.2f mm, overshoot %.1f %%  %s\n",
                  num("from_mm"), num("to_mm"), num("rise_s"), num("settling_s"), num("ess_mm"), num("overshoot_pct"),
                  m.value("passed", false) ? "pass" : "FAIL");
    out << buf;
  }
  return verdict == "deployed" ? 0 : verdict == "rolled-back" ? 2 : verdict == "aborted" ? 3 : 1;
}

}  // namespace epa::app
