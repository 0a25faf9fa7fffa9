#include "core/text_file.hpp"

#include <fstream>
#include <sstream>

namespace epa::core {

Result<std::string> read_text_file(const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) return io_error(path + ": cannot open the " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return io_error(path + ": cannot read the " + what);
  return ss.str();
}

}  // namespace epa::core
