#pragma once
// Names and other free text that reach the log, the store, `epa tuning list` and the page: one
// line of printable UTF-8, bounded. No control character (C0, DEL, C1: ESC and newline included),
// no line or paragraph separator, no bidirectional override, so that a name can never forge a log
// line, move a terminal's cursor or reorder what an operator reads. One rule for every reader and
// interface (tuning files, the CLI, HTTP).
#include <cstddef>
#include <string>
#include <string_view>

#include "core/result.hpp"

namespace epa::core {

inline constexpr std::size_t kMaxNameChars = 64;

// A name: 1 to max_chars printable characters, not only blanks. The message names `what` and
// the rule: "set name holds a control character (byte 5, 0x1b): a name is 1 to 64 printable
// characters on one line".
Status check_printable_name(std::string_view text, std::string_view what, std::size_t max_chars = kMaxNameChars);

// Free text (a source, a description): the same characters and tab, empty allowed, up to max_chars.
Status check_printable_text(std::string_view text, std::string_view what, std::size_t max_chars);

// `text` for a message, ASCII only: every byte outside printable ASCII as \xNN (so a C1 control or a
// cut sequence cannot reach a terminal), cut to max_chars bytes with "...".
std::string visible_text(std::string_view text, std::size_t max_chars = 40);

}  // namespace epa::core
