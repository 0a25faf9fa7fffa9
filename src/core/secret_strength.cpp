#include "core/secret_strength.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <set>
#include <vector>

namespace epa::core {

namespace {

constexpr std::size_t kMinTokenLength = 16;
constexpr std::size_t kLongTokenLength = 24;   // long enough that two character classes will do
constexpr std::size_t kMaxTokenLength = 256;   // an HTTP header's worth; also bounds the checks below
constexpr std::size_t kMinDistinct = 8;
constexpr std::size_t kLongRun = 6;            // same character, a sequence, or a part that occurs twice

// The words a guesser tries first, in lower case. Not hex words: a hex token (secrets.token_hex)
// would contain one too often.
constexpr std::array kCommonWords = {"password", "passwd", "pass",  "admin",   "secret",  "changeme", "letmein", "qwerty",
                                     "azerty",   "welcome", "token", "epa",    "login",   "master",   "default", "iloveyou",
                                     "monkey",   "dragon",  "trustno", "shadow", "sunshine", "football", "guest",  "root",
                                     "test",     "demo",    "user",   "hello",  "abc123",  "qwertz",   "asdf",    "zxcv"};

// Hex words as digits spell them (0 for o, 1 for i or l, 5 for s).
constexpr std::array kHexWords = {"dead", "beef", "cafe", "babe", "face",   "feed",   "fade",   "bead",  "deaf",
                                  "deed", "c0de", "f00d", "d00d", "b00b",   "ba5e",   "ca5e",   "5eed",  "1dea",
                                  "c0ffee", "0ff1ce", "dec0de", "decade", "facade", "acce55", "1337", "abba"};

// The token in lower case with digits read as the letters they stand in for: p4ssw0rd -> password.
// `one` is what 1 stands for (i or l).
std::string as_letters(std::string_view token, char one) {
  std::string out;
  for (char c : token) {
    switch (c) {
      case '0': out += 'o'; break;
      case '1': out += one; break;
      case '3': out += 'e'; break;
      case '4': case '@': out += 'a'; break;
      case '5': case '$': out += 's'; break;
      case '7': out += 't'; break;
      default: out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
  }
  return out;
}

// Words of 5 letters or more are also found spelt with digits; shorter ones only as written, or a
// random token would contain one too often (7e57 reads "test").
constexpr std::size_t kSpeltWithDigitsFrom = 5;

std::string common_word_in(std::string_view token) {
  std::string as_written(token);
  std::transform(as_written.begin(), as_written.end(), as_written.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const std::string with_i = as_letters(token, 'i'), with_l = as_letters(token, 'l');
  for (const std::string_view word : kCommonWords) {
    // A short word inside a long random token is chance, not a weakness ("epa" is in about 1 of
    // 1,200 random 24-character base64 tokens, what the advice makes): from 24 characters on it
    // counts only when it is a quarter of the token or more.
    if (token.size() >= kLongTokenLength && word.size() < kSpeltWithDigitsFrom && word.size() * 4 < token.size()) continue;
    if (as_written.find(word) != std::string::npos) return std::string(word);
    if (word.size() >= kSpeltWithDigitsFrom && (with_i.find(word) != std::string::npos || with_l.find(word) != std::string::npos))
      return std::string(word);
  }
  return "";
}

std::size_t longest_same_run(std::string_view s) {
  std::size_t best = 0, run = 0;
  for (std::size_t i = 0; i < s.size(); ++i) best = std::max(best, run = (i > 0 && s[i] == s[i - 1]) ? run + 1 : 1);
  return best;
}

// The longest run of letters or digits each one up (or each one down) from the last: abcdef, 654321.
std::size_t longest_sequence(std::string_view s) {
  std::size_t best = 1, up = 1, down = 1;
  for (std::size_t i = 1; i < s.size(); ++i) {
    const auto a = static_cast<unsigned char>(s[i - 1]), b = static_cast<unsigned char>(s[i]);
    const bool same_kind = std::isalnum(a) && std::isalnum(b) && (std::isdigit(a) != 0) == (std::isdigit(b) != 0);
    up = same_kind && b == a + 1 ? up + 1 : 1;
    down = same_kind && b + 1 == a ? down + 1 : 1;
    best = std::max({best, up, down});
  }
  return best;
}

// A part of `length` characters that occurs twice (overlapping counts: abcabcabc has abcabc twice).
std::string repeated_part(std::string_view s, std::size_t length) {
  if (s.size() < length + 1) return "";
  std::set<std::string_view> seen;
  for (std::size_t i = 0; i + length <= s.size(); ++i)
    if (!seen.insert(s.substr(i, length)).second) return std::string(s.substr(i, length));
  return "";
}

int character_classes(std::string_view s) {
  bool lower = false, upper = false, digit = false, other = false;
  for (unsigned char c : s) {
    if (std::islower(c)) lower = true;
    else if (std::isupper(c)) upper = true;
    else if (std::isdigit(c)) digit = true;
    else other = true;
  }
  return lower + upper + digit + other;
}

}  // namespace

std::string token_weakness(std::string_view token) {
  if (token.size() < kMinTokenLength)
    return "must be at least " + std::to_string(kMinTokenLength) + " characters, got " + std::to_string(token.size());
  if (token.size() > kMaxTokenLength) return "must be at most " + std::to_string(kMaxTokenLength) + " characters";
  for (unsigned char c : token)
    if (c <= ' ' || c >= 0x7f) return "must be printable ASCII without spaces (a header carries it)";
  if (const std::string word = common_word_in(token); !word.empty()) return "contains the common word '" + word + "'";
  if (longest_same_run(token) >= kLongRun) return "repeats one character " + std::to_string(kLongRun) + " or more times in a row";
  if (std::set<char>(token.begin(), token.end()).size() < kMinDistinct)
    return "has fewer than " + std::to_string(kMinDistinct) + " different characters";
  if (longest_sequence(token) >= kLongRun) return "has a run such as 123456 or abcdef";
  if (!repeated_part(token, kLongRun).empty()) return "repeats a part of " + std::to_string(kLongRun) + " characters (abcabcabc...)";
  if (character_classes(token) < 3 && token.size() < kLongTokenLength)
    return "needs 3 of: lower case, upper case, digits, other characters (or at least " + std::to_string(kLongTokenLength) +
           " characters)";
  return "";
}

std::string hex_words_weakness(std::string_view digits) {
  std::vector<bool> covered(digits.size(), false);
  std::vector<std::string> found;
  for (const std::string_view word : kHexWords) {
    bool hit = false;
    for (std::size_t at = digits.find(word); at != std::string_view::npos; at = digits.find(word, at + 1)) {
      std::fill(covered.begin() + static_cast<std::ptrdiff_t>(at), covered.begin() + static_cast<std::ptrdiff_t>(at + word.size()), true);
      hit = true;
    }
    if (hit) found.emplace_back(word);
  }
  const auto count = static_cast<std::size_t>(std::count(covered.begin(), covered.end(), true));
  if (digits.empty() || 2 * count < digits.size()) return "";
  std::string words;
  for (const auto& w : found) words += (words.empty() ? "" : ", ") + w;
  return "is mostly well-known hex words (" + words + "): among the first keys an attacker tries";
}

}  // namespace epa::core
