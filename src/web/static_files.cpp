#include "web/static_files.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace epa::web {

namespace {

// The content type for a page file's name, or "" if it is not one.
std::string content_type(std::string_view name) {
  const auto dot = name.rfind('.');
  const std::string_view ext = dot == std::string_view::npos ? "" : name.substr(dot);
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".json") return "application/json";
  if (ext == ".ico") return "image/x-icon";
  return "";
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// Reads `name` below `root_fd`: the body, or why it cannot be served.
core::Result<std::string> read_below(int root_fd, const std::string& name) {
  const Fd fd(::openat(root_fd, name.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK | O_NOCTTY));
  if (fd.get() < 0)
    return core::io_error(errno == ELOOP ? std::string("a symbolic link (only regular files are served)") : std::strerror(errno));
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return core::io_error(std::strerror(errno));
  if (!S_ISREG(st.st_mode)) return core::io_error("not a regular file");
  if (st.st_nlink != 1) return core::io_error("has " + std::to_string(st.st_nlink) + " hard links (only a file with one is served)");
  if (static_cast<std::size_t>(st.st_size) > StaticFiles::kMaxFileBytes)
    return core::io_error("larger than " + std::to_string(StaticFiles::kMaxFileBytes) + " bytes");
  std::string body(static_cast<std::size_t>(st.st_size), '\0');
  std::size_t got = 0;
  while (got < body.size()) {  // bounded by the size fstat gave: a file that grows is cut there
    const ssize_t n = ::read(fd.get(), body.data() + got, body.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return core::io_error(std::strerror(errno));
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  body.resize(got);
  return body;
}

}  // namespace

core::Result<StaticFiles> StaticFiles::load(const std::string& dir, const std::vector<std::string>& required) {
  const Fd root(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (root.get() < 0) return core::io_error("web: static_dir '" + dir + "' cannot be opened as a folder: " + std::strerror(errno));
  DIR* listing = ::fdopendir(::dup(root.get()));
  if (!listing) return core::io_error("web: static_dir '" + dir + "' cannot be listed: " + std::strerror(errno));
  std::vector<std::string> names;
  while (const dirent* e = ::readdir(listing)) {
    const std::string name = e->d_name;
    if (name.empty() || name[0] == '.' || content_type(name).empty()) continue;
    names.push_back(name);
  }
  ::closedir(listing);

  StaticFiles out;
  for (const auto& name : names) {
    if (out.files_.size() >= kMaxFiles) {
      out.skipped.push_back(name + " (more than " + std::to_string(kMaxFiles) + " files)");
      continue;
    }
    auto body = read_below(root.get(), name);
    if (!body) {
      out.skipped.push_back(name + " (" + body.error().message + ")");
      continue;
    }
    out.files_[name] = StaticFile{std::move(*body), content_type(name)};
  }
  for (const auto& name : required) {
    if (out.files_.count(name)) continue;
    std::string why = "(missing)";
    for (const auto& s : out.skipped)
      if (s.rfind(name + " (", 0) == 0) why = s.substr(name.size() + 1);
    return core::io_error("web: static_dir '" + dir + "' does not hold the page's " + name + " " + why +
                          " (it must be the folder of web/: index.html, app.js, style.css)");
  }
  return out;
}

const StaticFile* StaticFiles::find(std::string_view path) const {
  std::string_view name = path == "/" ? std::string_view("index.html") : path;
  if (!name.empty() && name.front() == '/') name.remove_prefix(1);
  if (name.empty() || name.find('/') != std::string_view::npos) return nullptr;  // no folders, so no ".."
  const auto it = files_.find(name);
  return it == files_.end() ? nullptr : &it->second;
}

}  // namespace epa::web
