#pragma once
// Stages a private OpenNI2 whose drivers directory holds only handtrack's virtual driver, and runs
// a process against it (see test_virtual_device.cpp for why this is how OpenNI2 is redirected).

#include <string>

namespace handtrack::test {

// The virtual driver's plug file: the device is plugged in while this path exists.
inline constexpr const char* kPlugFileEnv = "HANDTRACK_VDEV_PLUG_FILE";
// The virtual driver's stall file: while it exists the device sends no frames but stays listed.
inline constexpr const char* kStallFileEnv = "HANDTRACK_VDEV_STALL_FILE";
// Set in the child process to the staged directory.
inline constexpr const char* kStageDirEnv = "HANDTRACK_ONI_STAGE_DIR";

// Creates DIR/libOpenNI2.so.0 (a copy of the system library) and DIR/OpenNI2/Drivers/ holding a
// link to the virtual driver, under a fresh temporary directory. Returns DIR; throws on failure.
std::string stage_openni2();

// In the parent (no kStageDirEnv): stages, re-runs this executable with LD_LIBRARY_PATH=DIR,
// kStageDirEnv=DIR, kPlugFileEnv=DIR/plugged and kStallFileEnv=DIR/stalled, removes DIR and returns the child's exit
// status. In the child: returns -1 and the caller runs the tests.
int run_in_staged_openni2(int argc, char** argv);

// Empty when this process really uses the staged libOpenNI2, else what is wrong.
std::string staged_openni2_problem();

}  // namespace handtrack::test
