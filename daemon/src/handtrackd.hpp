#pragma once
// handtrackd as a function, so that the production program (main.cpp) and the test build
// (tests/daemon/faulty_handtrackd.cpp, with fault-injecting sources) are the same daemon.
#include "handtrack/daemon/depth_source.hpp"

#include <functional>
#include <memory>
#include <string>

namespace handtrack::daemon {

// Builds the source named by --source / daemon.source; the production one is make_source().
using SourceFactory = std::function<std::unique_ptr<DepthSource>(const std::string& spec, const SourceOptions&)>;

// The whole program: command line, configuration, ring, pipeline, signals, systemd. Returns the
// exit code.
int run_handtrackd(int argc, char** argv, const SourceFactory& make_source);

}  // namespace handtrack::daemon
