#pragma once
// Reader and writer of run files, format epa-run/1 (docs/formats.md): `#` comments, `# key=value`
// metadata (Ts in seconds, controller, source, ...), one CSV header row, one row per sample.
// Readers keep reading epa-run/1 when later versions appear; a file tagged with another
// version is refused, a file without a tag (hand-made export) is read if it parses.
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>

#include "core/result.hpp"
#include "core/run.hpp"

namespace epa::core {

// A number as a run file holds it (a metadata value or a field): finite, surrounding blanks and a
// leading '+' allowed; nullopt otherwise. Values are written with format_exact (core/format.hpp).
std::optional<double> parse_number(std::string_view text);

// Writes `run` as epa-run/1: version line, `# Ts=...`, then run.metadata in order, header, rows.
// Columns written: t_s, r_mm (if non-empty), y_mm, u_V, uc_V (if non-empty).
// t_s gets 6 decimals, mm columns 4, volt columns 5 (locale-independent). Failures show in the
// stream state; nothing is checked here (write_run_file checks), unequal columns are cut to
// the shortest one and a "Ts" key in run.metadata is skipped (Ts is written from run.Ts).
void write_run(std::ostream& out, const Run& run);

// io_error naming the path on failure; write to a temp file in the same folder then rename, so a
// reader never sees half a file. Refuses (invalid_argument) a run that read_run_file would not
// read back: no samples, unequal column lengths, non-finite values, Ts not > 0, non-uniform
// time, metadata keys that are not [A-Za-z0-9_.-]+ or values with line breaks, unknown controller.
Status write_run_file(const std::string& path, const Run& run);

// The most samples a run file may hold: 2,000,000 (2.8 h at Ts = 5 ms, about 100 MB read), so
// `identify` and `diagnose` have bounded memory whatever file they are given.
inline constexpr std::size_t kMaxRunSamples = 2'000'000;
// The most bytes a run file may have, 160 MiB: kMaxRunSamples rows of up to 80 bytes (write_run
// writes about 50). A larger file, or anything that is not a regular file, is refused unread.
inline constexpr std::size_t kMaxRunFileBytes = std::size_t{160} << 20;
// The longest line a run file may have: a header or a row is far shorter, and a message that
// quotes a line stays readable.
inline constexpr std::size_t kMaxRunLineBytes = 4096;

// Parses epa-run/1. `source_name` is used in messages ("runs/a.csv:14: ..."). If expected_Ts is
// given, the file's Ts must equal it (relative tolerance 1e-9) and a mismatch is an error naming
// both values. A file without `# Ts=` is checked against expected_Ts when given (and takes it as
// its Ts), else its Ts is inferred from the samples. Errors are parse errors (io_error if the
// stream fails); no exception escapes.
Result<Run> parse_run(std::istream& in, const std::string& source_name,
                      std::optional<double> expected_Ts = std::nullopt);

// parse_run on the file at `path` (used as the source name); io_error when it cannot be read, is
// not a regular file or is larger than kMaxRunFileBytes (core/text_file.hpp).
Result<Run> read_run_file(const std::string& path, std::optional<double> expected_Ts = std::nullopt);

}  // namespace epa::core
