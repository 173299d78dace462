#pragma once
// OpenNI2 sources: a live camera (the first device, or a given URI) and an .oni recording played
// through OpenNI2 itself (its OniFile driver).

#include "handtrack/daemon/depth_source.hpp"

#include <memory>
#include <string>

namespace handtrack::daemon {

// `uri` empty: the first device that appears. Unplug and replug are handled: grab() reports
// kDisconnected, the pipeline closes and reopens (a disconnected openni::Device is never reused).
std::unique_ptr<DepthSource> make_openni2_camera(const std::string& uri, const SourceOptions& options);
// Plays FILE.oni through OpenNI2 (at its own frame rate unless options.as_fast_as_possible).
std::unique_ptr<DepthSource> make_oni_recording(const std::string& file, const SourceOptions& options);

}  // namespace handtrack::daemon
