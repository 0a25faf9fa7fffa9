#pragma once
// Reading a TOML file's text, for every TOML reader: a syntax error as "file:line: what", and for
// the versioned formats of docs/formats.md the "schema" key checked against the one the reader knows.
#include <string>
#include <string_view>
#include <toml++/toml.h>

#include "core/result.hpp"
#include "core/toml_at_line.hpp"

namespace epa::core {

inline Result<toml::table> parse_toml(const std::string& text, const std::string& file) {
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    return parse_error(at_line(file, e.source()) + std::string(e.description()));
  }
}

// The document whose top-level "schema" names `schema` exactly (a file of another format or
// version is refused, naming both).
inline Result<toml::table> parse_toml_with_schema(const std::string& text, const std::string& file, std::string_view schema) {
  auto root = parse_toml(text, file);
  if (!root) return root;
  const auto expected = "(expected \"" + std::string(schema) + "\")";
  const auto node = (*root)["schema"];
  if (!node) return parse_error(file + ": schema is missing " + expected);
  const auto found = node.value<std::string>();
  if (!found) return parse_error(at_line(file, node.node()->source()) + "schema is not a string " + expected);
  if (*found != schema) return parse_error(file + ": schema \"" + *found + "\" is not supported " + expected);
  return root;
}

}  // namespace epa::core
