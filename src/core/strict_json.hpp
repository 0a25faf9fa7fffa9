#pragma once
// JSON as every reader of ours takes it (design files, commission specs, HTTP bodies): well-formed
// UTF-8, nested at most kMaxJsonDepth levels, each key once per object. The library's own messages
// are never passed on: they can quote the bytes that broke the parse (invalid UTF-8 that no JSON
// answer can carry) and a deep document would otherwise be parsed whole before anything is said.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "core/result.hpp"

namespace epa::core {

inline constexpr int kMaxJsonDepth = 64;

// `what` names the text in messages (a path, "the request body", "commission spec"):
//   "<what>: not valid UTF-8 JSON (byte 12)"
//   "<what>: nested deeper than 64 levels"
//   "<what>: duplicate key 'setpoint_mm' (each key may appear once)"
//   "<what>: not valid JSON: parse error at line 1, column 22"
Result<nlohmann::json> parse_strict_json(std::string_view text, const std::string& what);

}  // namespace epa::core
