#pragma once
// The recorder's directory under a quota. The run files the recorder writes
// (move-*, record-*, excite-*.csv) are counted with their sizes, oldest first;
// once they hold more than the quota, the oldest are deleted until they fit
// again. Files of other names are never touched or counted. Built from the
// directory once at start, then kept up to date by the writer: no scan per
// file. Not thread-safe: the recorder's thread owns it.
#include <cstdint>
#include <deque>
#include <functional>
#include <string>

namespace epa::runtime {

class RunDirectoryQuota {
public:
  using Log = std::function<void(const std::string &)>;
  RunDirectoryQuota(std::string directory, std::uint64_t quota_bytes,
                    Log log = {});

  // A file the recorder has just written: counted, then the oldest deleted
  // while over the quota (never the file just written). Returns how many were
  // deleted.
  std::size_t add(const std::string &path);

  std::uint64_t used_bytes() const { return used_bytes_; }
  std::size_t files() const { return files_.size(); }
  std::uint64_t deleted() const { return deleted_; }

  // Whether `name` is a file the recorder writes (and so under the quota).
  static bool is_run_file(const std::string &name);

private:
  struct File {
    std::string path;
    std::uint64_t bytes = 0;
  };
  std::string directory_;
  std::uint64_t quota_bytes_;
  Log log_;
  std::deque<File> files_; // oldest first
  std::uint64_t used_bytes_ = 0;
  std::uint64_t deleted_ = 0;
};

} // namespace epa::runtime
