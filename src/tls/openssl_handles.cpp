#include "tls/openssl_handles.hpp"

#include <openssl/err.h>

namespace epa::tls {

std::string take_openssl_errors(const std::string& fallback) {
  std::string text;
  while (const unsigned long e = ERR_get_error()) {
    char line[256];
    ERR_error_string_n(e, line, sizeof line);
    if (!text.empty()) text += "; ";
    text += line;
  }
  return text.empty() ? fallback : text;
}

}  // namespace epa::tls
