#pragma once
// The HTTP side of the subcommands that talk to a running appliance (`epa commission`,
// `epa records`): a client for --url with the timeouts they share, the bearer header of the
// token, and a failed answer in words: the appliance's own error text (its JSON "error"), or why
// no answer came, naming the URL.
#include <httplib.h>

#include <memory>
#include <string>

#include "core/result.hpp"

namespace epa::app {

// A client of `url` (http://HOST:PORT); an error naming --url when it is not one.
core::Result<std::unique_ptr<httplib::Client>> appliance_client(const std::string& url);
httplib::Headers bearer(const std::string& token);
// The [web] token: from --token-file (its first line), else --token or EPA_TOKEN (CLI11 fills
// `token` from either). A token on the command line shows in `ps`; the file or the variable do not.
// An error naming where to give it when there is none, or naming the file it could not read.
core::Result<std::string> appliance_token(const std::string& token, const std::string& token_file);
// "HTTP 400: <the appliance's error>", or "no answer from <url>: <why>".
std::string http_failure(const httplib::Result& r, const std::string& url);

}  // namespace epa::app
