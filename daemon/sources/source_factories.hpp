#pragma once
// The factory of each source folder, called only by make_source() (make_source.cpp), the one
// public entry point for sources (handtrack/daemon/depth_source.hpp). Each throws
// std::invalid_argument naming the source when its argument is unusable.
#include "handtrack/daemon/depth_source.hpp"

#include <memory>
#include <string>

namespace handtrack::daemon {

// openni2/: `uri` empty: the first device that appears. Unplug and replug are handled: grab()
// reports kDisconnected, the pipeline closes and reopens (a disconnected device is never reused).
std::unique_ptr<DepthSource> make_openni2_camera(const std::string& uri, const SourceOptions& options);
// oni/: plays FILE.oni through OpenNI2 (at its own frame rate unless options.as_fast_as_possible).
std::unique_ptr<DepthSource> make_oni_recording(const std::string& file, const SourceOptions& options);
// sequence/: `seq:DIR` (SPEC.md "Sequence directory"). A PNG that is missing, corrupt or not of
// camera.json's size is reported as GrabStatus::kError (skipped and counted) with the reason in
// last_error().
std::unique_ptr<DepthSource> make_sequence_source(const std::string& dir, const SourceOptions& options);
// isolated/: an OpenNI2 source (openni2, openni2:URI, oni:FILE) run by handtrack-source-helper in
// a child process; a fault in OpenNI2 or a driver ends the helper, grab() returns kFailed.
std::unique_ptr<DepthSource> make_isolated_source(const std::string& spec, const SourceOptions& options);
// The OpenNI2 sources in this process: what the helper runs (isolated/source_helper.cpp).
std::unique_ptr<DepthSource> make_driver_source(const std::string& spec, const SourceOptions& options);
// synthetic/: `motion` empty: cycle through all seven. Unknown motion: std::invalid_argument.
std::unique_ptr<DepthSource> make_synthetic_source(const std::string& motion, const SourceOptions& options);

}  // namespace handtrack::daemon
