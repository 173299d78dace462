#pragma once
// The one form of an error reading or writing a file (png_io.cpp, sequence.cpp): "FILE: what".
#include <filesystem>
#include <stdexcept>
#include <string>

namespace handtrack {

[[noreturn]] inline void throw_file_error(const std::filesystem::path& file, const std::string& what) {
  throw std::runtime_error(file.string() + ": " + what);
}

}  // namespace handtrack
