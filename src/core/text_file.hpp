#pragma once
// A whole text file as a string, for the readers of our file formats (model, configuration,
// register map, plant parameters, tuning files). The error names the file and what it is.
#include <string>

#include "core/result.hpp"

namespace epa::core {

// `what` names the file's role in the message: "<path>: cannot open the <what>".
Result<std::string> read_text_file(const std::string& path, const std::string& what);

}  // namespace epa::core
