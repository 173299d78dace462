// libFuzzer + ASan/UBSan: the PNG readers (core/src/png_io.cpp) on arbitrary bytes, with the size
// a sequence's camera.json gives (what handtrack-eval, handtrack-view and the seq: source do).
// A bad file must throw one std::runtime_error; never crash, leak or allocate beyond the frame.
#include "fuzz_input.hpp"

#include "handtrack/core/png_io.hpp"

#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const auto file = handtrack::fuzz::scratch("frame.png");
  handtrack::fuzz::write_file(file, data, size);
  const handtrack::PngSize expected{64, 48};
  try {
    (void)handtrack::read_png_gray16(file, expected);
  } catch (const std::runtime_error&) {
  }
  try {
    (void)handtrack::read_png_gray8(file, expected);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
