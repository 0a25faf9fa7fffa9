#include "app/appliance_http.hpp"

#include <nlohmann/json.hpp>

namespace epa::app {

core::Result<std::unique_ptr<httplib::Client>> appliance_client(const std::string& url) {
  auto client = std::make_unique<httplib::Client>(url);
  if (!client->is_valid()) return core::invalid_argument("--url '" + url + "' is not http://HOST:PORT");
  client->set_connection_timeout(5, 0);
  client->set_read_timeout(10, 0);
  return client;
}

httplib::Headers bearer(const std::string& token) { return {{"Authorization", "Bearer " + token}}; }

std::string http_failure(const httplib::Result& r, const std::string& url) {
  if (!r) return "no answer from " + url + " (" + httplib::to_string(r.error()) + "): is the appliance running there, with its [web] port?";
  const auto j = nlohmann::json::parse(r->body, nullptr, false);
  if (j.is_object() && j.contains("error") && j["error"].is_string()) return "HTTP " + std::to_string(r->status) + ": " + j["error"].get<std::string>();
  return "HTTP " + std::to_string(r->status);
}

}  // namespace epa::app
