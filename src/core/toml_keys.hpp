#pragma once
// Every key of a TOML table must be one the reader knows: a misspelt key is refused with its name
// and line, never left out in silence (a misspelt `mm_per_vlot = 25` would run on the default
// 50 mm/V). One wording for every TOML file the product reads (the model and
// tuning files, the physics parameters, the configuration), in the compiler's form editors jump to:
//   file:line: unknown key 'key' in [table] (expected one of: a, b, c)
// (" in [table]" left out at the top level; the place as core::at_line() writes it).
#include <initializer_list>
#include <span>
#include <string>
#include <string_view>
#include <toml++/toml.h>

#include "core/result.hpp"
#include "core/toml_at_line.hpp"

namespace epa::core {

inline Error unknown_key(const std::string& file, const toml::source_region& where, std::string_view key,
                         std::string_view table, std::span<const std::string_view> expected) {
  std::string names;
  for (const std::string_view e : expected) names += (names.empty() ? "" : ", ") + std::string(e);
  return parse_error(at_line(file, where) + "unknown key '" + std::string(key) + "'" +
                     (table.empty() ? std::string() : " in [" + std::string(table) + "]") + " (expected one of: " + names + ")");
}

// The first key of `t` that is not in `allowed`, as unknown_key(); `table`: its name, "" at the top.
inline Status only_keys(const toml::table& t, std::span<const std::string_view> allowed, const std::string& file,
                        std::string_view table = {}) {
  for (const auto& [key, node] : t) {
    bool known = false;
    for (const std::string_view a : allowed) known = known || key.str() == a;
    if (!known) return unknown_key(file, node.source(), key.str(), table, allowed);
  }
  return ok();
}

inline Status only_keys(const toml::table& t, std::initializer_list<std::string_view> allowed, const std::string& file,
                        std::string_view table = {}) {
  return only_keys(t, std::span<const std::string_view>(allowed.begin(), allowed.size()), file, table);
}

}  // namespace epa::core
