#pragma once
// An output file that a tool writes at the end of a long run is checked at its start, so that a
// path it cannot write is one error line at once, not after minutes of tracking, measuring or
// training.

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>

namespace handtrack::tools {

// Throws "PATH: cannot write" unless `path` can be opened for writing (an empty path passes). It
// creates and truncates nothing: a file already there stays as it is until the tool replaces it,
// so a run that fails on the way leaves the last run's output in place.
inline void check_writable(const std::string& path) {
  if (path.empty()) return;
  std::error_code ignored;
  const bool existed = std::filesystem::exists(path, ignored);
  const bool writable = std::ofstream(path, std::ios::app).good();
  if (!existed) std::filesystem::remove(path, ignored);
  if (!writable) throw std::runtime_error(path + ": cannot write");
}

}  // namespace handtrack::tools
