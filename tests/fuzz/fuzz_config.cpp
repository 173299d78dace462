// libFuzzer + ASan/UBSan: handtrackd's TOML configuration (daemon/src/config.cpp parse_config)
// on arbitrary text. A bad configuration must throw one ConfigError; never crash or hang.
#include "handtrack/daemon/config.hpp"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)handtrack::daemon::parse_config(text, "fuzz.toml");
  } catch (const handtrack::daemon::ConfigError&) {
  }
  return 0;
}
