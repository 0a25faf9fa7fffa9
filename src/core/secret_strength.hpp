#pragma once
// How strong a secret must be before the appliance takes it: the HTTP token ([web] token,
// EPA_TOKEN, --token-file) and the Modbus unlock key ([modbus] unlock_key). The rules refuse what
// an attacker tries first, not what a random generator gives: a token from
// `head -c 18 /dev/urandom | base64` or a key from `od -An -tx8 -N8 /dev/urandom` passes all but
// about one time in a thousand (then the message says why, and another draw passes).
#include <string>
#include <string_view>

namespace epa::core {

// How to make a good token, for the messages of every reader of one.
inline constexpr const char* kTokenAdvice = "make one with `head -c 18 /dev/urandom | base64`";

// "" when `token` is strong enough; else why not, in words (without the advice). Rules: printable
// ASCII without spaces; at least 16 characters; 3 of the classes lower case, upper case, digit,
// other, or at least 24 characters; at least 8 different characters; no character 6 times in a
// row; no run of 6 such as 123456 or abcdef; no 6 characters that occur twice (abcabcabc...); no
// common word (password, admin, secret, token, ...), also spelt with digits (p4ssw0rd).
std::string token_weakness(std::string_view token);

// "" when the hex digits `digits` (lower case) are not mostly well-known hex words; else why.
// A key such as deadbeefcafebabe is among the first an attacker tries: words such as dead, beef,
// cafe, babe, face, feed, c0de, c0ffee, f00d covering half the digits or more refuse it.
std::string hex_words_weakness(std::string_view digits);

}  // namespace epa::core
