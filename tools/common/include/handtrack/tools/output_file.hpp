#pragma once
// An output file that a tool writes at the end of a long run is opened at its start, so that a
// path it cannot write is one error line at once, not after minutes of tracking or measuring.

#include <fstream>
#include <stdexcept>
#include <string>

namespace handtrack::tools {

// Opens `path` for writing into `stream` (an empty path leaves it closed); throws
// "PATH: cannot write" where it cannot.
inline void open_output(const std::string& path, std::ofstream& stream) {
  if (path.empty()) return;
  stream.open(path);
  if (!stream) throw std::runtime_error(path + ": cannot write");
}

}  // namespace handtrack::tools
