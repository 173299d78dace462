// libFuzzer + ASan/UBSan: the sequence CSV readers (groundtruth.csv, joints.csv; core/src/
// sequence.cpp) on arbitrary bytes, inside an otherwise valid sequence directory. The first byte
// picks the file (bit 0) and whether hand.json names two hands (bit 1: two blocks per row). A bad
// file must throw one std::runtime_error.
#include "fuzz_input.hpp"

#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"

#include <stdexcept>

namespace {

// camera.json and one depth frame, made once.
std::filesystem::path sequence_dir() {
  static const std::filesystem::path dir = [] {
    const auto d = handtrack::fuzz::scratch("sequence");
    std::filesystem::create_directories(d / "depth");
    handtrack::CameraIntrinsics camera;
    camera.width = 16;
    camera.height = 12;
    camera.cx = 8;
    camera.cy = 6;
    handtrack::write_camera_json(d / "camera.json", camera);
    handtrack::Gray16Image frame;
    frame.width = 16;
    frame.height = 12;
    frame.pixels.assign(16 * 12, 500);
    handtrack::write_png_gray16(d / "depth" / "000000.png", frame);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const auto dir = sequence_dir();
  const bool joints = (data[0] & 1) != 0;
  std::filesystem::remove(dir / "groundtruth.csv");
  std::filesystem::remove(dir / "joints.csv");
  std::filesystem::remove(dir / "hand.json");
  if ((data[0] & 2) != 0) handtrack::write_hand_json(dir / "hand.json", {"right", "left"});
  handtrack::fuzz::write_file(dir / (joints ? "joints.csv" : "groundtruth.csv"), data + 1, size - 1);
  try {
    const handtrack::SequenceReader reader(dir);
    for (int hand = 0; hand < reader.hand_count(); ++hand) {
      (void)reader.fingertips(0, hand);
      (void)reader.joints(0, hand);
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
