// print_poses (C++): the smallest C++ client, over the RAII wrapper handtrack/client.hpp.
// Prints each new frame with every hand in it: id, handedness, state, index fingertip and pinch.
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
  handtrack_frame frame{};
  long printed = 0;
  while (printed < count) {
    const int status = client.wait_next(frame, std::chrono::seconds(2));
    if (status == HANDTRACK_OK) {
      std::printf("frame %llu (missed %llu):", static_cast<unsigned long long>(frame.frame),
                  static_cast<unsigned long long>(client.missed()));
      const handtrack::Hands hands = handtrack::hands(frame);
      if (hands.empty()) std::printf(" no hand");
      for (const handtrack_hand& hand : hands) {
        const float* tip = hand.fingertips_mm[1];  // index finger (thumb = 0)
        std::printf("%s hand %u %s %s index tip %.1f %.1f %.1f mm pinch %.1f mm", &hand == hands.begin() ? "" : ";",
                    static_cast<unsigned>(hand.hand_id), handtrack_handedness_name(hand.handedness),
                    handtrack_state_name(hand.state), static_cast<double>(tip[0]), static_cast<double>(tip[1]),
                    static_cast<double>(tip[2]), static_cast<double>(hand.pinch_distance_mm));
      }
      std::printf("\n");
      ++printed;
    } else if (status == HANDTRACK_TIMEOUT) {
      std::fprintf(stderr, "print_poses_cpp: no frame for 2 s\n");
      return 1;
    } else if (status != HANDTRACK_ERR_WRITER_DEAD && status != HANDTRACK_ERR_WRITER_STOPPED) {
      std::fprintf(stderr, "print_poses_cpp: %s\n", handtrack::Client::describe(status).c_str());
      return 1;
    }
    // A dead or stopped daemon: keep waiting, the client follows a restarted one by itself.
  }
  return 0;
}
