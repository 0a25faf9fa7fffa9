#pragma once
// The Host header check against DNS rebinding: a hostile page whose name is made to resolve to the
// appliance reaches it from an operator's browser, and the browser lets the page read the answers
// because the name is the page's own. The request still carries that name as its Host, so only
// names the appliance knows as its own are served: an IP literal of the appliance's host (or any
// loopback address), "localhost", the host's name, and the names listed in [web] host_names.
#include <chrono>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace epa::web {

class HostCheck {
 public:
  explicit HostCheck(const std::vector<std::string>& host_names);

  // Whether a request whose Host header is `host` ("name", "name:port", "[v6]:port"; empty: a
  // client that sent none, which no browser does) and that came in on `local_addr` may be served.
  bool allowed(std::string_view host, const std::string& local_addr);

 private:
  bool is_local_address(const std::string& literal);

  std::set<std::string> names_;  // lower case, without a trailing dot
  std::mutex mutex_;
  std::set<std::string> addresses_;  // the host's, refreshed now and then (DHCP may change them)
  std::chrono::steady_clock::time_point refreshed_{};
};

// The host part of a Host header value, lower case, without port, brackets or trailing dot.
std::string host_part(std::string_view host);

}  // namespace epa::web
