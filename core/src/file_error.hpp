#pragma once
// The one form of a file reader's error (png_io.cpp, sequence.cpp): "FILE: what".
#include <filesystem>
#include <stdexcept>
#include <string>

namespace handtrack {

[[noreturn]] inline void fail_reading(const std::filesystem::path& file, const std::string& what) {
  throw std::runtime_error(file.string() + ": " + what);
}

}  // namespace handtrack
