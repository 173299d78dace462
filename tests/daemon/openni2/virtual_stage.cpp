#include "virtual_stage.hpp"

#include <OniCAPI.h>

#include <dlfcn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace handtrack::test {

std::string stage_openni2() {
  std::string pattern = (fs::temp_directory_path() / "handtrack-oni2-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp " + pattern + " failed");
  const fs::path dir = pattern;
  // A copy, not a symlink: OpenNI2 resolves its own path with realpath() and looks for drivers
  // beside the real file.
  fs::copy_file(fs::canonical(HANDTRACK_OPENNI2_LIBRARY), dir / "libOpenNI2.so.0");
  fs::create_directories(dir / "OpenNI2" / "Drivers");
  fs::create_symlink(HANDTRACK_VIRTUAL_DRIVER, dir / "OpenNI2" / "Drivers" / "libhandtrack_virtual_depth.so.0");
  return dir.string();
}

int run_in_staged_openni2(int argc, char** argv) {
  (void)argc;
  if (std::getenv(kStageDirEnv) != nullptr) return -1;
  const std::string dir = stage_openni2();
  const pid_t pid = fork();
  if (pid < 0) return 1;
  if (pid == 0) {
    const char* old = std::getenv("LD_LIBRARY_PATH");
    // (Appended piecewise: GCC 12 reports a false -Wrestrict for `":" + std::string(old)`.)
    std::string path = dir;
    if (old != nullptr && *old != '\0') path.append(":").append(old);
    setenv("LD_LIBRARY_PATH", path.c_str(), 1);
    setenv(kStageDirEnv, dir.c_str(), 1);
    setenv(kPlugFileEnv, (dir + "/plugged").c_str(), 1);
    setenv(kStallFileEnv, (dir + "/stalled").c_str(), 1);
    execv("/proc/self/exe", argv);
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

std::string staged_openni2_problem() {
  const char* dir = std::getenv(kStageDirEnv);
  if (dir == nullptr) return "not running in a staged OpenNI2 (main() must call run_in_staged_openni2)";
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&oniInitialize), &info) == 0 || info.dli_fname == nullptr) {
    return "cannot tell where libOpenNI2 was loaded from";
  }
  char real[PATH_MAX];
  const std::string loaded = realpath(info.dli_fname, real) ? real : info.dli_fname;
  const std::string staged = fs::canonical(fs::path(dir) / "libOpenNI2.so.0").string();
  if (loaded != staged) {
    return "libOpenNI2 was loaded from " + loaded + ", not from the staged " + staged +
           " (LD_LIBRARY_PATH overridden by an RPATH?)";
  }
  return {};
}

}  // namespace handtrack::test
