#pragma once
// The accept queue of every listening socket of the appliance (Modbus and HTTP). A burst of
// connects (an HMI farm reconnecting, or a flood) beyond the queue has its SYNs dropped, and a
// dropped SYN is retried by the client's kernel only after 1 s: with cpp-httplib's built-in 5 an
// operator's poll during a burst of 50 connects waited 1.0 s. The kernel caps it at somaxconn.
namespace epa::core {

inline constexpr int kListenBacklog = 1024;

}  // namespace epa::core
