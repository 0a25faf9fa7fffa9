#include "core/run_file.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <exception>
#include <istream>
#include <ostream>
#include <streambuf>
#include <string_view>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/format.hpp"
#include "core/text_file.hpp"
#include "core/units.hpp"

namespace epa::core {
namespace {

constexpr std::string_view kVersionTag = "epa-run/1";
constexpr std::string_view kVersionPrefix = "epa-run/";
constexpr std::string_view kBom = "\xEF\xBB\xBF";
constexpr std::array<std::string_view, 5> kControllers = {"pp", "pp-ngidz", "pp-ffidz", "pp-traj", "open-loop"};

struct ColumnSpec {
  std::string_view name;
  std::vector<double> Run::*member;
  bool required;
  int decimals;  // written; enough for what matters (1 us, 0.1 um, 10 uV)
};
// Also the order in which write_run writes them.
constexpr std::array<ColumnSpec, 5> kColumns = {{{"t_s", &Run::t_s, true, 6},
                                                 {"r_mm", &Run::r_mm, false, 4},
                                                 {"y_mm", &Run::y_mm, true, 4},
                                                 {"u_V", &Run::u_V, true, 5},
                                                 {"uc_V", &Run::uc_V, false, 5}}};

std::string_view trim(std::string_view s) {
  constexpr std::string_view kSpace = " \t\r\n\v\f";
  const auto first = s.find_first_not_of(kSpace);
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(kSpace) - first + 1);
}

// Restricting keys keeps free-text comments such as "# tuned by hand, gain=3" out of metadata.
bool is_meta_key(std::string_view key) {
  if (key.empty()) return false;
  return std::all_of(key.begin(), key.end(), [](unsigned char c) {
    return std::isalnum(c) != 0 || c == '_' || c == '.' || c == '-';
  });
}

bool is_controller(std::string_view name) {
  return std::find(kControllers.begin(), kControllers.end(), name) != kControllers.end();
}

std::string approx(double v) {  // for steps in messages: 0.01 rather than 0.010000000000000002
  char buf[64];
  return std::string(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 9).ptr);
}

void append_fixed(std::string& line, double v, int decimals) {
  char buf[400];  // enough for any finite double in fixed notation with 6 decimals
  const auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  std::string_view text = res.ec == std::errc() ? std::string_view(buf, res.ptr - buf) : "nan";
  // "-0.0000" would read back as -0; print it as 0.
  if (text.front() == '-' && text.find_first_not_of("0.", 1) == std::string_view::npos) text.remove_prefix(1);
  line += text;
}

double step_tolerance(double Ts) { return std::max(1e-6, 1e-3 * Ts); }

// Index k of the first sample whose step from k-1 is not Ts, or 0 when all are uniform.
std::size_t first_bad_step(const std::vector<double>& t, double Ts) {
  for (std::size_t k = 1; k < t.size(); ++k)
    if (!(std::abs((t[k] - t[k - 1]) - Ts) <= step_tolerance(Ts))) return k;
  return 0;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  for (;;) {
    const auto comma = line.find(',');
    fields.push_back(trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return fields;
    line.remove_prefix(comma + 1);
  }
}

Error error_at(const std::string& source, std::size_t line, const std::string& message) {
  return parse_error(source + ":" + std::to_string(line) + ": " + message);
}

std::string quoted_list(const std::vector<std::string_view>& names) {
  std::string out;
  for (const auto name : names) out += (out.empty() ? "'" : ", '") + std::string(name) + "'";
  return out;
}

Result<Run> parse_run_impl(std::istream& in, const std::string& src, std::optional<double> expected_Ts) {
  if (expected_Ts && !(std::isfinite(*expected_Ts) && *expected_Ts > 0.0))
    return invalid_argument(src + ": expected Ts must be a positive number of seconds, got " + format_exact(*expected_Ts));
  Run run;
  std::optional<double> file_Ts;
  std::size_t ts_line = 0, header_line = 0, line_no = 0;
  std::vector<std::vector<double>*> targets;  // per header column: where its values go, or null
  std::vector<std::string> column_names;
  std::vector<std::size_t> row_lines;         // file line of each sample, for messages
  std::string raw;
  while (std::getline(in, raw)) {
    std::string_view line = raw;
    if (raw.size() > kMaxRunLineBytes)
      return error_at(src, line_no + 1, "line longer than " + std::to_string(kMaxRunLineBytes) + " bytes: not a run file");
    if (++line_no == 1 && line.starts_with(kBom)) line.remove_prefix(kBom.size());
    line = trim(line);  // also drops the '\r' of CRLF files
    if (line.empty()) continue;
    if (line.front() == '#') {
      const std::string_view body = trim(line.substr(1));
      if (body.starts_with(kVersionPrefix)) {
        if (body != kVersionTag)
          return error_at(src, line_no, "unsupported format version '" + std::string(body) + "', this reader reads " +
                                            std::string(kVersionTag));
        continue;
      }
      const auto eq = body.find('=');
      const std::string_view key = trim(body.substr(0, eq));
      if (eq == std::string_view::npos || !is_meta_key(key)) continue;  // a plain comment
      const std::string_view value = trim(body.substr(eq + 1));
      if (key == "Ts") {
        if (file_Ts) return error_at(src, line_no, "Ts given twice (first on line " + std::to_string(ts_line) + ")");
        file_Ts = parse_number(value);
        if (!file_Ts || *file_Ts <= 0.0)
          return error_at(src, line_no, "Ts must be a positive number of seconds, got '" + std::string(value) + "'");
        ts_line = line_no;
      } else {
        if (key == "controller" && !is_controller(value))
          return error_at(src, line_no, "unknown controller '" + std::string(value) +
                                            "', expected one of pp, pp-ngidz, pp-ffidz, pp-traj, open-loop");
        run.metadata.emplace_back(key, value);
      }
      continue;
    }
    const auto fields = split_fields(line);
    if (header_line == 0) {
      header_line = line_no;
      for (std::size_t j = 0; j < fields.size(); ++j)
        for (std::size_t i = 0; i < j; ++i)
          if (!fields[j].empty() && fields[i] == fields[j])
            return error_at(src, line_no, "duplicate column '" + std::string(fields[j]) + "' in the header");
      targets.assign(fields.size(), nullptr);
      column_names.assign(fields.begin(), fields.end());
      std::vector<std::string_view> missing;
      for (const auto& spec : kColumns) {
        const auto it = std::find(fields.begin(), fields.end(), spec.name);
        if (it != fields.end()) targets[static_cast<std::size_t>(it - fields.begin())] = &(run.*spec.member);
        else if (spec.required) missing.push_back(spec.name);
      }
      if (!missing.empty())
        return error_at(src, line_no, std::string("header row: missing required column") +
                                          (missing.size() > 1 ? "s " : " ") + quoted_list(missing) +
                                          " (found columns: " + quoted_list(fields) + ")");
      continue;
    }
    if (row_lines.size() >= kMaxRunSamples)
      return error_at(src, line_no, "more than " + std::to_string(kMaxRunSamples) +
                                        " samples (the most a run file may hold, 2.8 h at 5 ms): split the recording");
    if (fields.size() != targets.size())
      return error_at(src, line_no, "expected " + std::to_string(targets.size()) + " fields as in the header, got " +
                                        std::to_string(fields.size()));
    for (std::size_t j = 0; j < fields.size(); ++j) {
      if (targets[j] == nullptr) continue;  // unknown column: ignored, not even parsed
      const auto value = parse_number(fields[j]);
      if (!value)
        return error_at(src, line_no, "column '" + column_names[j] + "': expected a finite number, got '" +
                                          std::string(fields[j]) + "'");
      targets[j]->push_back(*value);
    }
    row_lines.push_back(line_no);
  }
  if (in.bad()) return io_error(src + ": read error after line " + std::to_string(line_no));
  if (header_line == 0)
    return line_no == 0 ? parse_error(src + ": empty file, expected a header row (t_s,y_mm,u_V) and data rows")
                        : error_at(src, line_no, "no header row, expected a header such as t_s,y_mm,u_V");
  if (row_lines.empty()) return error_at(src, header_line, "header without data rows, expected at least one sample");

  const auto& t = run.t_s;  // Ts: the file's, else the model's, else inferred
  std::string origin;
  if (file_Ts) {
    if (expected_Ts && !same_sample_time(*file_Ts, *expected_Ts))
      // The reader does not know whose Ts it was given: a model's, or the first run's (identify).
      return error_at(src, ts_line, "Ts=" + format_exact(*file_Ts) + " s in the file, but " + format_exact(*expected_Ts) +
                                        " s is expected (the model's Ts, or the other runs')");
    run.Ts = *file_Ts;
  } else if (expected_Ts) {
    run.Ts = *expected_Ts;
    origin = " (the model's Ts; the file has no Ts line)";
  } else {
    if (t.size() < 2)
      return error_at(src, row_lines[0], "no '# Ts=' line and a single sample, expected at least two to infer Ts");
    run.Ts = t[1] - t[0];
    if (!(run.Ts > 0.0))
      return error_at(src, row_lines[1], "t_s must increase, got " + approx(t[0]) + " then " + approx(t[1]));
    origin = " (inferred from the first two samples)";
  }
  if (const auto k = first_bad_step(t, run.Ts); k != 0)
    return error_at(src, row_lines[k], "non-uniform time: expected a step of Ts=" + approx(run.Ts) + " s" + origin +
                                           ", got " + approx(t[k] - t[k - 1]) + " s (t_s " + approx(t[k - 1]) +
                                           " -> " + approx(t[k]) + ")");
  // The mean step is more precise than the first one when times are printed with few decimals.
  if (!file_Ts && !expected_Ts) run.Ts = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  return run;
}

// What read_run_file would refuse, so that write_run_file never writes a file we cannot read back.
Status check_writable(const Run& run) {
  if (!(std::isfinite(run.Ts) && run.Ts > 0.0)) return invalid_argument("Ts must be > 0 s, got " + format_exact(run.Ts));
  const std::size_t n = run.t_s.size();
  if (n == 0) return invalid_argument("the run has no samples");
  for (const auto& spec : kColumns) {
    const auto& column = run.*spec.member;
    if (column.empty() && !spec.required) continue;
    if (column.size() != n)
      return invalid_argument("column " + std::string(spec.name) + " has " + std::to_string(column.size()) +
                              " values, t_s has " + std::to_string(n));
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(column[k]))
        return invalid_argument("column " + std::string(spec.name) + " sample " + std::to_string(k) + " is not finite");
  }
  if (const auto k = first_bad_step(run.t_s, run.Ts); k != 0)
    return invalid_argument("non-uniform time at sample " + std::to_string(k) + ": step " +
                            approx(run.t_s[k] - run.t_s[k - 1]) + " s, Ts " + approx(run.Ts) + " s");
  for (const auto& [key, value] : run.metadata) {
    if (!is_meta_key(key) || key == "Ts") return invalid_argument("metadata key '" + key + "' cannot be written");
    if (value.find_first_of("\r\n") != std::string::npos)
      return invalid_argument("metadata value of '" + key + "' contains a line break");
    if (key == "controller" && !is_controller(value)) return invalid_argument("unknown controller '" + value + "'");
  }
  return ok();
}

// A stream over text already read, without the copy an istringstream makes of up to 160 MiB.
class TextBuffer : public std::streambuf {
 public:
  explicit TextBuffer(std::string& text) { setg(text.data(), text.data(), text.data() + text.size()); }
};

std::string one_line(std::string text) {
  std::replace_if(text.begin(), text.end(), [](char c) { return c == '\r' || c == '\n'; }, ' ');
  return text;
}

}  // namespace

std::optional<double> parse_number(std::string_view text) {
  text = trim(text);
  if (text.size() > 1 && text.front() == '+' && text[1] != '-') text.remove_prefix(1);  // from_chars refuses '+'
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

void write_run(std::ostream& out, const Run& run) {
  try {
    std::string line = "# " + std::string(kVersionTag) + "\n# Ts=" + format_exact(run.Ts) + "\n";
    for (const auto& [key, value] : run.metadata)
      if (key != "Ts") line += "# " + one_line(key) + "=" + one_line(value) + "\n";
    std::vector<const ColumnSpec*> columns;
    std::size_t n = run.t_s.size();
    for (const auto& spec : kColumns) {
      const auto& column = run.*spec.member;
      if (column.empty() && !spec.required) continue;
      columns.push_back(&spec);
      n = std::min(n, column.size());
    }
    for (std::size_t j = 0; j < columns.size(); ++j) line += (j ? "," : "") + std::string(columns[j]->name);
    line += '\n';
    out << line;
    for (std::size_t k = 0; k < n && out; ++k) {
      line.clear();
      for (std::size_t j = 0; j < columns.size(); ++j) {
        if (j) line += ',';
        append_fixed(line, (run.*(columns[j]->member))[k], columns[j]->decimals);
      }
      line += '\n';
      out << line;
    }
  } catch (...) {  // bad_alloc, or a stream with exceptions enabled: report through the stream state
    try { out.setstate(std::ios::badbit); } catch (...) {}  // NOLINT(bugprone-empty-catch)
  }
}

Status write_run_file(const std::string& path, const Run& run) {
  if (auto status = check_writable(run); !status)
    return invalid_argument("cannot write run file '" + path + "': " + status.error().message);
  // Readers see the old file or the whole new one.
  if (auto s = write_file_atomically(path, [&run](std::ostream& out) { write_run(out, run); }); !s)
    return io_error("cannot write run file '" + path + "': " + s.error().message);
  return ok();
}

Result<Run> parse_run(std::istream& in, const std::string& source_name, std::optional<double> expected_Ts) {
  try {
    return parse_run_impl(in, source_name, expected_Ts);
  } catch (const std::exception& e) {  // bad_alloc, or a stream with exceptions enabled
    return io_error(source_name + ": cannot read: " + e.what());
  }
}

Result<Run> read_run_file(const std::string& path, std::optional<double> expected_Ts) {
  try {
    auto text = read_text_file(path, "run file", kMaxRunFileBytes);
    if (!text) return text.error();
    TextBuffer buffer(*text);
    std::istream in(&buffer);
    return parse_run(in, path, expected_Ts);
  } catch (const std::exception& e) {
    return io_error("cannot read run file '" + path + "': " + e.what());
  }
}

}  // namespace epa::core
