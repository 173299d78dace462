// libFuzzer + ASan/UBSan: camera.json (core/src/sequence.cpp read_camera_json) on arbitrary bytes.
// A bad file must throw one std::runtime_error naming it; intrinsics that come back are usable.
#include "fuzz_input.hpp"

#include "handtrack/core/sequence.hpp"

#include <cstdlib>
#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const auto file = handtrack::fuzz::scratch("camera.json");
  handtrack::fuzz::write_file(file, data, size);
  try {
    const handtrack::CameraIntrinsics camera = handtrack::read_camera_json(file);
    if (!camera.problem().empty()) std::abort();  // accepted but unusable: a finding
  } catch (const std::runtime_error&) {
  }
  return 0;
}
