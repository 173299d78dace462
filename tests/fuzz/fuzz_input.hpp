#pragma once
// What the file-reader fuzz targets share: the readers take paths, so each input is written to a
// scratch file of this process first (in the temporary directory; removed at exit).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace handtrack::fuzz {

// A file named `name` in a scratch directory of this process.
inline std::filesystem::path scratch(const std::string& name) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("handtrack-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    static const struct Remover {
      std::filesystem::path path;
      ~Remover() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
      }
    } remover{d};
    return d;
  }();
  return dir / name;
}

inline void write_file(const std::filesystem::path& file, const uint8_t* data, size_t size) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

}  // namespace handtrack::fuzz
