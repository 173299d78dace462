// Writes with the C++ writer (as the daemon does) and reads back through the C API's C++ wrapper.
#include <handtrack/client.hpp>
#include <handtrack/ipc/pose_ring_writer.hpp>

#include <cstdio>
#include <string>

#include <unistd.h>

int main() {
  using handtrack::ipc::PoseRingWriter;
  const std::string name = "ht_consumer_" + std::to_string(::getpid());
  int rc = 1;
  {
    PoseRingWriter writer(PoseRingWriter::Options{.name = name, .capacity = 4});
    handtrack::ipc::FrameRecord frame{};
    frame.frame = 5;
    frame.hand_count = 1;
    frame.hands[0].hand_id = 1;
    frame.hands[0].handedness = HANDTRACK_HANDEDNESS_RIGHT;
    frame.hands[0].state = HANDTRACK_STATE_TRACKING;
    writer.publish(frame);
    handtrack::Client client;
    handtrack_frame out{};
    if (const int st = client.open(name); st != HANDTRACK_OK) {
      std::fprintf(stderr, "consumer: %s\n", handtrack::Client::describe(st).c_str());
    } else if (client.latest(out) == HANDTRACK_OK && out.frame == 5 && out.epoch == writer.epoch() &&
               handtrack::hands(out).size() == 1 && handtrack::hands(out)[0].handedness == HANDTRACK_HANDEDNESS_RIGHT) {
      std::puts("consumer_cpp ok");
      rc = 0;
    }
  }
  PoseRingWriter::remove(name);
  return rc;
}
