// make_source: SPEC.md "Sources" -> a DepthSource, the one public entry point for sources. Each
// scheme's source lives in its own folder (openni2/, oni/, sequence/, synthetic/); the OpenNI2
// ones run in a helper process through isolated/.
#include "handtrack/daemon/depth_source.hpp"

#include "source_factories.hpp"

#include <stdexcept>

namespace handtrack::daemon {

namespace {

struct SplitSpec {
  std::string scheme;
  std::string rest;
  bool has_argument = false;
};

SplitSpec split(const std::string& spec) {
  const auto colon = spec.find(':');
  return {spec.substr(0, colon), colon == std::string::npos ? std::string() : spec.substr(colon + 1),
          colon != std::string::npos};
}

bool is_driver_scheme(const std::string& scheme) { return scheme == "openni2" || scheme == "oni"; }

}  // namespace

std::unique_ptr<DepthSource> make_driver_source(const std::string& spec, const SourceOptions& options) {
  const SplitSpec s = split(spec);
  if (s.scheme == "openni2") {
    if (s.has_argument && s.rest.empty()) {
      throw std::invalid_argument("openni2:: the device URI after 'openni2:' is empty");
    }
    return make_openni2_camera(s.rest, options);
  }
  if (s.scheme == "oni") {
    if (s.rest.empty()) throw std::invalid_argument(spec + ": expected oni:FILE.oni");
    return make_oni_recording(s.rest, options);
  }
  throw std::invalid_argument("'" + spec + "': not an OpenNI2 source (openni2, openni2:URI, oni:FILE.oni)");
}

std::unique_ptr<DepthSource> make_source(const std::string& spec, const SourceOptions& options) {
  const SplitSpec s = split(spec);
  // OpenNI2 and its drivers run in a helper process (isolated/).
  if (is_driver_scheme(s.scheme)) return make_isolated_source(spec, options);
  if (s.scheme == "seq") {
    if (s.rest.empty()) throw std::invalid_argument(spec + ": expected seq:DIR");
    return make_sequence_source(s.rest, options);
  }
  if (s.scheme == "synthetic") {
    if (s.has_argument && s.rest.empty()) {
      throw std::invalid_argument("synthetic:: the motion after 'synthetic:' is empty");
    }
    return make_synthetic_source(s.rest, options);
  }
  throw std::invalid_argument("'" + spec +
                              "': unknown source (expected openni2, openni2:URI, oni:FILE.oni, seq:DIR or "
                              "synthetic[:MOTION])");
}

}  // namespace handtrack::daemon
