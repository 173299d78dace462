// Built when OpenNI2 was not found at configure time: both factories refuse with a clear message.
#include "../source_factories.hpp"

#include <stdexcept>

namespace handtrack::daemon {

std::unique_ptr<DepthSource> make_openni2_camera(const std::string& uri, const SourceOptions& /*options*/) {
  throw std::invalid_argument("openni2" + (uri.empty() ? std::string() : ":" + uri) +
                              ": handtrackd was built without OpenNI2 (install libopenni2-dev and rebuild)");
}

std::unique_ptr<DepthSource> make_oni_recording(const std::string& file, const SourceOptions& /*options*/) {
  throw std::invalid_argument("oni:" + file +
                              ": handtrackd was built without OpenNI2 (install libopenni2-dev and rebuild)");
}

}  // namespace handtrack::daemon
