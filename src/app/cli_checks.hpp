#pragma once
// Readable checks of numeric command-line options, for every subcommand. CLI11's PositiveNumber
// and NonNegativeNumber print their upper bound, the largest double, in 300 digits ("Value abc not
// in range 0.000000 to 17976931348623157..."), and say so of a word that is no number at all.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>

namespace epa::app::cli {

// A finite decimal number for which `holds` is true; the message names the text and the rule.
template <typename Rule>
CLI::Validator number_where(const std::string& rule_text, Rule holds) {
  return CLI::Validator(
      [rule_text, holds](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
          return "'" + text + "' is not a number (expected " + rule_text + ")";
        if (!holds(v)) return text + " is not " + rule_text;
        return {};
      },
      rule_text);
}

inline const CLI::Validator kPositive = number_where("a number > 0", [](double v) { return v > 0.0; });
inline const CLI::Validator kNonNegative = number_where("a number >= 0", [](double v) { return v >= 0.0; });

// A seed: a whole number >= 0 (an unsigned option would otherwise take "-3" as 2^64 - 3).
inline const CLI::Validator kSeed = CLI::Validator(
    [](std::string& text) -> std::string {
      if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos)
        return "'" + text + "' is not a seed (expected a whole number >= 0)";
      return {};
    },
    "a whole number >= 0");

}  // namespace epa::app::cli
