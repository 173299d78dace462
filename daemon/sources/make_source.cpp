// make_source: SPEC.md "Sources" -> a DepthSource, the one public entry point for sources. Each
// scheme's source lives in its own folder (openni2/, oni/, sequence/, synthetic/).
#include "handtrack/daemon/depth_source.hpp"

#include "source_factories.hpp"

#include <stdexcept>

namespace handtrack::daemon {

std::unique_ptr<DepthSource> make_source(const std::string& spec, const SourceOptions& options) {
  const auto colon = spec.find(':');
  const std::string scheme = spec.substr(0, colon);
  const std::string rest = colon == std::string::npos ? std::string() : spec.substr(colon + 1);
  const bool has_argument = colon != std::string::npos;
  if (scheme == "openni2") {
    if (has_argument && rest.empty()) throw std::invalid_argument("openni2:: the device URI after 'openni2:' is empty");
    return make_openni2_camera(rest, options);
  }
  if (scheme == "oni") {
    if (rest.empty()) throw std::invalid_argument(spec + ": expected oni:FILE.oni");
    return make_oni_recording(rest, options);
  }
  if (scheme == "seq") {
    if (rest.empty()) throw std::invalid_argument(spec + ": expected seq:DIR");
    return make_sequence_source(rest, options);
  }
  if (scheme == "synthetic") {
    if (has_argument && rest.empty()) throw std::invalid_argument("synthetic:: the motion after 'synthetic:' is empty");
    return make_synthetic_source(rest, options);
  }
  throw std::invalid_argument("'" + spec +
                              "': unknown source (expected openni2, openni2:URI, oni:FILE.oni, seq:DIR or "
                              "synthetic[:MOTION])");
}

}  // namespace handtrack::daemon
