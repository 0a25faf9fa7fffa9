#pragma once
// The addresses the appliance listens on ([modbus] address, [web] address) and the addresses of
// its peers, as text and as socket addresses. A listen address is an IPv4 dotted quad
// ("0.0.0.0", "192.168.0.5": four numbers 0-255, nothing else) or an IPv6 literal ("::1", "::");
// no host names (the appliance must not depend on a resolver to start). "::" listens on IPv6 and,
// as the kernel maps them, IPv4 too (the HTTP library does the same); a peer that came over IPv4
// is named by its dotted quad, so [modbus] write_clients lists IPv4 addresses as before.
#include <netinet/in.h>
#include <sys/socket.h>

#include <string>
#include <string_view>

#include "core/result.hpp"

namespace epa::core {

struct SocketAddress {
  sockaddr_storage storage{};
  socklen_t length = 0;
  int family() const { return storage.ss_family; }
};

// `text` and `port` as a socket address; an error saying what an address must look like.
Result<SocketAddress> parse_ip_address(std::string_view text, int port);
// true for the IPv4 dotted quad form only (an IPv6 literal is false).
bool is_ipv4_address(std::string_view text);

// The address alone: "10.0.0.5", "::1"; an IPv4-mapped IPv6 address (::ffff:10.0.0.5) as its
// IPv4 dotted quad. "?" for another family.
std::string ip_text(const sockaddr_storage& address);
// As a URL names the host: "10.0.0.5", "[::1]".
std::string url_host(const sockaddr_storage& address);
// With the port: "10.0.0.5:502", "[::1]:502".
std::string endpoint_text(const sockaddr_storage& address);
int port_of(const sockaddr_storage& address);

// What a listening socket is bound to (getsockname): endpoint_text, or "?" when it cannot tell.
std::string bound_endpoint(int socket_fd);

// A non-blocking TCP listener bound to `address` (SO_REUSEADDR, so a restart binds past
// TIME_WAIT; no SO_REUSEPORT, so a second appliance on the same port fails to start); "::" also
// takes IPv4 (IPV6_V6ONLY off), any other IPv6 address IPv6 only. The descriptor, or an error
// naming `where` and why.
Result<int> open_listener(const SocketAddress& address, int backlog, const std::string& where);

}  // namespace epa::core
