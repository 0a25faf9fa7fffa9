#pragma once
// A whole text file as a string, for every reader of our file formats (model, configuration,
// register map, plant parameters, design, tuning, commission spec, token and run files). Bounded:
// anything that is not a regular file (/dev/zero, a FIFO, a folder) is refused before reading, and
// so is a file above the caller's size cap, which is also enforced while reading (a file can grow).
// The error names the file, its role and what was wrong.
#include <cstddef>
#include <string>

#include "core/result.hpp"

namespace epa::core {

inline constexpr std::size_t kMiB = std::size_t{1} << 20;
// The hand-written formats (configuration, register map, model, design, tuning, commission spec,
// plant parameters) are a few KiB; 4 MiB leaves room for comments and still reads in milliseconds.
inline constexpr std::size_t kSmallFileCapBytes = 4 * kMiB;
inline constexpr std::size_t kDefaultTextFileCapBytes = 16 * kMiB;

// "<path>: cannot open the <what>: No such file or directory",
// "<path>: not a regular file (character device): cannot read the <what>",
// "<path>: 1073741824 bytes, above the 4 MiB cap for a <what>".
Result<std::string> read_text_file(const std::string& path, const std::string& what,
                                   std::size_t max_bytes = kDefaultTextFileCapBytes);

// "4 MiB", "64 KiB", "1000 bytes": a cap as the messages and the documentation say it.
std::string byte_size_text(std::size_t bytes);

}  // namespace epa::core
