#include "core/word_order.hpp"

#include <string>

namespace epa::core {

namespace {
constexpr std::pair<WordOrder, std::string_view> kNames[] = {
    {WordOrder::kABCD, "ABCD"}, {WordOrder::kCDAB, "CDAB"}, {WordOrder::kBADC, "BADC"}, {WordOrder::kDCBA, "DCBA"}};
}

std::string_view to_string(WordOrder order) {
  for (const auto& [o, name] : kNames)
    if (o == order) return name;
  return "ABCD";
}

Result<WordOrder> parse_word_order(std::string_view text) {
  for (const auto& [o, name] : kNames)
    if (name == text) return o;
  return invalid_argument("word order '" + std::string(text) + "' is not one of ABCD, CDAB, BADC, DCBA");
}

}  // namespace epa::core
