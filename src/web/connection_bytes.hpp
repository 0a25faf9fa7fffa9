#pragma once
// The bytes of one web connection, moved as far as the socket allows now and never waiting:
// straight on the socket (HTTP), or through the connection's TLS session (HTTPS), where what is
// read is decrypted and what is written encrypted. The front end and its workers call these
// alike, so the framing, the deadlines and the answers "as the client reads" are the same for both.
#include <cstddef>
#include <string>

#include "tls/tls_connection.hpp"

namespace epa::web {

enum class Received {
  kSome,   // bytes were appended; more may be waiting
  kNone,   // nothing has arrived: wait for the socket
  kEnded,  // the client closed, or the connection failed
};

// Appends to `into` what has arrived, at most `max_bytes` of it. `tls`: the session, or null.
Received receive_some(int fd, tls::TlsConnection* tls, std::string& into, std::size_t max_bytes);

enum class Sent {
  kAll,     // `out` is empty
  kWait,    // the socket takes no more now: wait for it to be writable
  kFailed,  // the connection is broken
};

// Sends from the front of `out` what the socket takes now, and erases what it took. With TLS,
// the bytes left in `out` are the ones the session must be given again (OpenSSL's rule after a
// write that could not finish).
Sent send_some(int fd, tls::TlsConnection* tls, std::string& out);

// Whether bytes wait inside the TLS session that the socket's readiness will not announce.
inline bool bytes_pending(const tls::TlsConnection* tls) { return tls && tls->has_pending(); }

}  // namespace epa::web
