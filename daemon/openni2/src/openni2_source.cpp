// Placeholder until the OpenNI2 sources land: both factories refuse with a clear message.
#include "handtrack/daemon/openni2_source.hpp"

#include <stdexcept>

namespace handtrack::daemon {

std::unique_ptr<DepthSource> make_openni2_camera(const std::string& uri, const SourceOptions& /*options*/) {
  throw std::invalid_argument("openni2" + (uri.empty() ? std::string() : ":" + uri) +
                              ": OpenNI2 support is not built yet");
}

std::unique_ptr<DepthSource> make_oni_recording(const std::string& file, const SourceOptions& /*options*/) {
  throw std::invalid_argument("oni:" + file + ": OpenNI2 support is not built yet");
}

}  // namespace handtrack::daemon
