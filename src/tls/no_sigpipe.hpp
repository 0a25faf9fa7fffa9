#pragma once
// OpenSSL writes to its socket with write(2), which raises SIGPIPE when the client has gone, and
// SIGPIPE ends the process. A thread that runs TLS connections blocks it for itself (threads it
// starts inherit the mask): such a write then fails with EPIPE, and the connection is closed.
#include <signal.h>

namespace epa::tls {

inline void block_sigpipe_on_this_thread() {
  sigset_t pipe;
  sigemptyset(&pipe);
  sigaddset(&pipe, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe, nullptr);
}

}  // namespace epa::tls
