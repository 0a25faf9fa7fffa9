// TOML text into the appliance configuration loader (config/epa.toml, epa-config/1): a config or
// an error naming the key or line, never a crash or an exception escaping the library.
#include <cstddef>
#include <cstdint>
#include <string>

#include "config/appliance_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)epa::config::parse_appliance_config(text, EPA_SOURCE_DIR "/config/fuzz.toml");
  return 0;
}
