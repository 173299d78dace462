// print_poses (C++): the smallest C++ client, over the RAII wrapper handtrack/client.hpp.
// Prints the frame, state, index fingertip and pinch of each new pose.
//   Build against the installed package: find_package(handtrack) + handtrack::client (see
//   CMakeLists.txt here), or  c++ -std=c++17 print_poses.cpp $(pkg-config --cflags --libs handtrack)
//   Usage: print_poses_cpp [SHM_NAME [COUNT]]
#include <handtrack/client.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  const std::string name = argc > 1 ? argv[1] : HANDTRACK_DEFAULT_SHM_NAME;
  const long count = argc > 2 ? std::strtol(argv[2], nullptr, 10) : 10;
  handtrack::Client client;
  if (const int status = client.open(name); status != HANDTRACK_OK) {
    std::fprintf(stderr, "print_poses_cpp: %s\n", handtrack::Client::describe(status).c_str());
    return 1;
  }
  handtrack_pose pose{};
  long printed = 0;
  while (printed < count) {
    const int status = client.wait_next(pose, std::chrono::seconds(2));
    if (status == HANDTRACK_OK) {
      const float* tip = pose.fingertips_mm[1];  // index finger (thumb = 0)
      std::printf("frame %llu %s index tip %.1f %.1f %.1f mm pinch %.1f mm (missed %llu)\n",
                  static_cast<unsigned long long>(pose.frame), handtrack_state_name(pose.state),
                  static_cast<double>(tip[0]), static_cast<double>(tip[1]),
                  static_cast<double>(tip[2]), static_cast<double>(pose.pinch_distance_mm),
                  static_cast<unsigned long long>(client.missed()));
      ++printed;
    } else if (status == HANDTRACK_TIMEOUT) {
      std::fprintf(stderr, "print_poses_cpp: no pose for 2 s\n");
      return 1;
    } else if (status != HANDTRACK_ERR_WRITER_DEAD && status != HANDTRACK_ERR_WRITER_STOPPED) {
      std::fprintf(stderr, "print_poses_cpp: %s\n", handtrack::Client::describe(status).c_str());
      return 1;
    }
    // A dead or stopped daemon: keep waiting, the client follows a restarted one by itself.
  }
  return 0;
}
