#include "app/appliance_http.hpp"

#include <nlohmann/json.hpp>

#include "core/secret_strength.hpp"
#include "core/text_file.hpp"

namespace epa::app {

core::Result<std::unique_ptr<httplib::Client>> appliance_client(const std::string& url) {
  auto client = std::make_unique<httplib::Client>(url);
  if (!client->is_valid()) return core::invalid_argument("--url '" + url + "' is not http://HOST:PORT");
  client->set_connection_timeout(5, 0);
  client->set_read_timeout(10, 0);
  return client;
}

httplib::Headers bearer(const std::string& token) { return {{"Authorization", "Bearer " + token}}; }

namespace {
// The appliance refuses a weak [web] token at start, so a weak one here is a typo or another
// appliance's: said before any request, naming where it came from.
core::Result<std::string> strong_token(std::string token, const std::string& source) {
  if (const std::string why = core::token_weakness(token); !why.empty())
    return core::invalid_argument(source + ": the token " + why + "; the appliance's [web] token is refused the same way (" +
                                  core::kTokenAdvice + ")");
  return token;
}
}  // namespace

core::Result<std::string> appliance_token(const std::string& token, const std::string& token_file) {
  if (token_file.empty()) {
    if (token.empty()) return core::invalid_argument("no token: set EPA_TOKEN, or give --token-file FILE (or --token, which shows in ps), with the appliance's [web] token");
    return strong_token(token, "EPA_TOKEN or --token");
  }
  auto text = core::read_text_file(token_file, "token file", 64 * 1024);  // a token is one line
  if (!text) return text.error();
  std::string first = text->substr(0, text->find('\n'));
  if (!first.empty() && first.back() == '\r') first.pop_back();
  if (first.empty()) return core::invalid_argument(token_file + ": the token file's first line is empty");
  return strong_token(std::move(first), token_file);
}

std::string http_failure(const httplib::Result& r, const std::string& url) {
  if (!r) return "no answer from " + url + " (" + httplib::to_string(r.error()) + "): is the appliance running there, with its [web] port?";
  const auto j = nlohmann::json::parse(r->body, nullptr, false);
  if (j.is_object() && j.contains("error") && j["error"].is_string()) return "HTTP " + std::to_string(r->status) + ": " + j["error"].get<std::string>();
  return "HTTP " + std::to_string(r->status);
}

}  // namespace epa::app
