#pragma once
// Progress of long work with an estimate of the time left, on stderr and only when stderr is a
// terminal (SPEC.md "Programs": quiet otherwise).

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace handtrack::tools {

class Progress {
 public:
  explicit Progress(std::string program) : program_(std::move(program)), enabled_(::isatty(STDERR_FILENO) == 1) {}
  void restart() { start_ = Clock::now(); }
  // `fraction` of the work is done, in [0, 1].
  void update(const std::string& stage, double fraction) {
    if (!enabled_) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const double left = fraction > 0.0 ? elapsed / fraction * (1.0 - fraction) : 0.0;
    std::fprintf(stderr, "\r%s: %s %3.0f%%, %.0f s left    ", program_.c_str(), stage.c_str(), 100.0 * fraction, left);
    std::fflush(stderr);
  }
  void done() {
    if (enabled_) std::fprintf(stderr, "\n");
  }

 private:
  using Clock = std::chrono::steady_clock;
  std::string program_;
  bool enabled_;
  Clock::time_point start_ = Clock::now();
};

}  // namespace handtrack::tools
