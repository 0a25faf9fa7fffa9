#include "core/ip_address.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace epa::core {

bool is_ipv4_address(std::string_view text) {
  in_addr a{};
  return ::inet_pton(AF_INET, std::string(text).c_str(), &a) == 1;  // glibc: exactly a.b.c.d, each 0-255
}

Result<SocketAddress> parse_ip_address(std::string_view text, int port) {
  SocketAddress out;
  const std::string s(text);
  if (auto& v4 = reinterpret_cast<sockaddr_in&>(out.storage); ::inet_pton(AF_INET, s.c_str(), &v4.sin_addr) == 1) {
    v4.sin_family = AF_INET;
    v4.sin_port = htons(static_cast<std::uint16_t>(port));
    out.length = sizeof(sockaddr_in);
    return out;
  }
  out.storage = {};
  if (auto& v6 = reinterpret_cast<sockaddr_in6&>(out.storage); ::inet_pton(AF_INET6, s.c_str(), &v6.sin6_addr) == 1) {
    v6.sin6_family = AF_INET6;
    v6.sin6_port = htons(static_cast<std::uint16_t>(port));
    out.length = sizeof(sockaddr_in6);
    return out;
  }
  return invalid_argument("'" + s + "' is not an IP address: give an IPv4 address such as 0.0.0.0 or 192.168.0.5 (four numbers 0-255)"
                          " or an IPv6 address such as :: or ::1 (no host names)");
}

std::string ip_text(const sockaddr_storage& a) {
  char text[INET6_ADDRSTRLEN] = "?";
  if (a.ss_family == AF_INET) {
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in&>(a).sin_addr, text, sizeof text);
  } else if (a.ss_family == AF_INET6) {
    const in6_addr& v6 = reinterpret_cast<const sockaddr_in6&>(a).sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&v6)) ::inet_ntop(AF_INET, &v6.s6_addr[12], text, sizeof text);  // "::" serving IPv4
    else ::inet_ntop(AF_INET6, &v6, text, sizeof text);
  }
  return text;
}

int port_of(const sockaddr_storage& a) {
  if (a.ss_family == AF_INET) return ntohs(reinterpret_cast<const sockaddr_in&>(a).sin_port);
  if (a.ss_family == AF_INET6) return ntohs(reinterpret_cast<const sockaddr_in6&>(a).sin6_port);
  return 0;
}

std::string url_host(const sockaddr_storage& a) {
  const std::string ip = ip_text(a);
  return ip.find(':') != std::string::npos ? "[" + ip + "]" : ip;
}

std::string endpoint_text(const sockaddr_storage& a) { return url_host(a) + ":" + std::to_string(port_of(a)); }

std::string bound_endpoint(int fd) {
  sockaddr_storage a{};
  socklen_t len = sizeof a;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) return "?";
  return endpoint_text(a);
}

Result<int> open_listener(const SocketAddress& address, int backlog, const std::string& where) {
  const int fd = ::socket(address.family(), SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  auto fail = [&](const char* step) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    return io_error("cannot listen on " + where + ": " + step + ": " + why +
                    (address.family() == AF_INET6 ? " (has this host IPv6, and that address?)" : ""));
  };
  if (fd < 0) return fail("socket");
  const int yes = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  if (address.family() == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(address.storage).sin6_addr;
    const int v6_only = IN6_IS_ADDR_UNSPECIFIED(&v6) ? 0 : 1;  // "::" takes IPv4 as well, like the HTTP server
    ::setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &v6_only, sizeof v6_only);
  }
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address.storage), address.length) != 0) return fail("bind");
  if (::listen(fd, backlog) != 0) return fail("listen");
  return fd;
}

}  // namespace epa::core
