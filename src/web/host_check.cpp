#include "web/host_check.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>

namespace epa::web {

namespace {

constexpr auto kRefreshPeriod = std::chrono::seconds(10);

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// The canonical text of an IP literal ("::FFFF:127.0.0.1" -> "127.0.0.1"), or "" if it is none.
std::string canonical_address(const std::string& text) {
  in_addr v4{};
  if (::inet_pton(AF_INET, text.c_str(), &v4) == 1) {
    std::array<char, INET_ADDRSTRLEN> out{};
    ::inet_ntop(AF_INET, &v4, out.data(), out.size());
    return out.data();
  }
  in6_addr v6{};
  if (::inet_pton(AF_INET6, text.c_str(), &v6) != 1) return "";
  if (IN6_IS_ADDR_V4MAPPED(&v6)) {
    std::copy_n(v6.s6_addr + 12, 4, reinterpret_cast<unsigned char*>(&v4));
    std::array<char, INET_ADDRSTRLEN> out{};
    ::inet_ntop(AF_INET, &v4, out.data(), out.size());
    return out.data();
  }
  std::array<char, INET6_ADDRSTRLEN> out{};
  ::inet_ntop(AF_INET6, &v6, out.data(), out.size());
  return out.data();
}

bool is_loopback(const std::string& canonical) { return canonical.rfind("127.", 0) == 0 || canonical == "::1"; }

std::set<std::string> machine_addresses() {
  std::set<std::string> out;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return out;
  for (const ifaddrs* i = list; i; i = i->ifa_next) {
    if (!i->ifa_addr) continue;
    std::array<char, INET6_ADDRSTRLEN> text{};
    if (i->ifa_addr->sa_family == AF_INET)
      ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr, text.data(), text.size());
    else if (i->ifa_addr->sa_family == AF_INET6)
      ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr, text.data(), text.size());
    else
      continue;
    out.insert(canonical_address(text.data()));
  }
  ::freeifaddrs(list);
  return out;
}

}  // namespace

std::string host_part(std::string_view host) {
  std::string_view h = host;
  if (!h.empty() && h.front() == '[') {
    const auto close = h.find(']');
    h = close == std::string_view::npos ? h.substr(1) : h.substr(1, close - 1);
  } else if (std::count(h.begin(), h.end(), ':') == 1) {
    h = h.substr(0, h.find(':'));
  }
  if (!h.empty() && h.back() == '.') h.remove_suffix(1);
  return lower(h);
}

HostCheck::HostCheck(const std::vector<std::string>& host_names) {
  for (const auto& n : host_names) {
    const std::string name = host_part(n);
    const std::string address = canonical_address(name);
    names_.insert(address.empty() ? name : address);
  }
  names_.insert("localhost");
  std::array<char, 256> hostname{};
  if (::gethostname(hostname.data(), hostname.size() - 1) == 0 && hostname[0] != '\0') {
    const std::string full = lower(hostname.data());
    names_.insert(full);
    names_.insert(full.substr(0, full.find('.')));
  }
}

bool HostCheck::is_local_address(const std::string& literal) {
  std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (addresses_.empty() || now - refreshed_ >= kRefreshPeriod) addresses_ = machine_addresses(), refreshed_ = now;
  return addresses_.count(literal) != 0;
}

bool HostCheck::allowed(std::string_view host, const std::string& local_addr) {
  if (host.empty()) return true;
  const std::string name = host_part(host);
  const std::string address = canonical_address(name);
  if (address.empty()) return names_.count(name) != 0;
  return is_loopback(address) || address == canonical_address(local_addr) || names_.count(address) != 0 || is_local_address(address);
}

}  // namespace epa::web
