#include "runtime/run_directory_quota.hpp"

#include <algorithm>
#include <filesystem>
#include <vector>

namespace epa::runtime {

namespace fs = std::filesystem;

bool RunDirectoryQuota::is_run_file(const std::string &name) {
  const bool ours = name.starts_with("move-") || name.starts_with("record-") ||
                    name.starts_with("excite-");
  return ours && name.ends_with(".csv");
}

RunDirectoryQuota::RunDirectoryQuota(std::string directory,
                                     std::uint64_t quota_bytes, Log log)
    : directory_(std::move(directory)), quota_bytes_(quota_bytes),
      log_(std::move(log)) {
  struct Found {
    fs::file_time_type time;
    File file;
  };
  std::vector<Found> found;
  std::error_code ec;
  for (auto it = fs::directory_iterator(directory_, ec);
       !ec && it != fs::directory_iterator(); it.increment(ec)) {
    std::error_code e;
    if (!it->is_regular_file(e) || !is_run_file(it->path().filename().string()))
      continue;
    const auto bytes = it->file_size(e);
    const auto time = it->last_write_time(e);
    if (!e)
      found.push_back({time, {it->path().string(), bytes}});
  }
  std::sort(found.begin(), found.end(),
            [](const Found &a, const Found &b) { return a.time < b.time; });
  for (Found &f : found) {
    used_bytes_ += f.file.bytes;
    files_.push_back(std::move(f.file));
  }
}

std::size_t RunDirectoryQuota::add(const std::string &path) {
  std::error_code ec;
  const auto bytes = fs::file_size(path, ec);
  files_.push_back({path, ec ? 0 : bytes});
  used_bytes_ += files_.back().bytes;
  std::size_t deleted = 0;
  while (used_bytes_ > quota_bytes_ && files_.size() > 1) {
    const File oldest = files_.front();
    files_.pop_front();
    used_bytes_ -= oldest.bytes;
    std::error_code e;
    fs::remove(oldest.path, e); // gone already (an operator cleaned up): no
                                // longer counted either way
    ++deleted;
  }
  deleted_ += deleted;
  if (deleted > 0 && log_)
    log_("recorder: deleted the " + std::to_string(deleted) +
         " oldest run file(s) to stay within the quota (" +
         std::to_string(quota_bytes_ / (1024 * 1024)) + " MiB)");
  return deleted;
}

} // namespace epa::runtime
