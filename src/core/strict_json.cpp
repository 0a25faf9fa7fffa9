#include "core/strict_json.hpp"

#include <set>
#include <vector>

#include "core/printable_name.hpp"
#include "core/utf8.hpp"

namespace epa::core {

namespace {

// Thrown from the parser's callback to stop it at once; carries our message.
struct Refusal {
  std::string message;
};

std::string line_and_column(std::string_view text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') ++line, column = 1;
    else ++column;
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

Result<nlohmann::json> parse_strict_json(std::string_view text, const std::string& what) {
  using nlohmann::json;
  if (const auto bad = first_invalid_utf8(text)) return parse_error(what + ": not valid UTF-8 JSON (byte " + std::to_string(*bad) + ")");
  std::vector<std::set<std::string>> keys_seen;  // one set per open object
  auto check = [&](int depth, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        if (depth >= kMaxJsonDepth) throw Refusal{what + ": nested deeper than " + std::to_string(kMaxJsonDepth) + " levels"};
        if (event == json::parse_event_t::object_start) keys_seen.emplace_back();
        break;
      case json::parse_event_t::object_end:
        if (!keys_seen.empty()) keys_seen.pop_back();
        break;
      case json::parse_event_t::key:
        if (!keys_seen.empty() && !keys_seen.back().insert(parsed.get<std::string>()).second)
          throw Refusal{what + ": duplicate key '" + visible_text(parsed.get<std::string>()) + "' (each key may appear once)"};
        break;
      default:
        break;
    }
    return true;
  };
  try {
    return json::parse(text, check);
  } catch (const Refusal& r) {
    return parse_error(r.message);
  } catch (const json::parse_error& e) {  // our words and position: the library's text may quote what broke it
    return parse_error(what + ": not valid JSON: parse error at " + line_and_column(text, e.byte > 0 ? e.byte - 1 : 0));
  } catch (const json::out_of_range&) {  // 1e999
    return parse_error(what + ": a number is beyond the range of a double");
  } catch (const json::exception&) {
    return parse_error(what + ": not valid JSON");
  }
}

}  // namespace epa::core
