#pragma once
// Every key of a TOML table must be one the reader knows: a misspelt key is refused with its name
// and line, never left out in silence (a model file's `mm_per_vlot = 25` ran on the default
// 50 mm/V until 2026-11-29). Shared by the files' readers (model, tuning).
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <toml++/toml.h>

#include "core/result.hpp"

namespace epa::core {

inline Status only_keys(const toml::table& table, std::span<const std::string_view> allowed, const std::string& where) {
  for (const auto& [key, node] : table) {
    bool known = false;
    for (const std::string_view a : allowed) known = known || key.str() == a;
    if (known) continue;
    std::string names;
    for (const std::string_view a : allowed) names += (names.empty() ? "" : ", ") + std::string(a);
    const auto line = node.source().begin.line;
    return parse_error(where + ": unknown key '" + std::string(key.str()) + "' (" +
                       (line > 0 ? "line " + std::to_string(line) + "; " : std::string()) + "expected one of: " + names + ")");
  }
  return ok();
}

inline Status only_keys(const toml::table& table, std::initializer_list<std::string_view> allowed, const std::string& where) {
  return only_keys(table, std::span<const std::string_view>(allowed.begin(), allowed.size()), where);
}

}  // namespace epa::core
