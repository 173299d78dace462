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
    handtrack::ipc::PoseRecord pose{};
    pose.frame = 5;
    pose.state = HANDTRACK_STATE_TRACKING;
    writer.publish(pose);
    handtrack::Client client;
    handtrack_pose out{};
    if (const int st = client.open(name); st != HANDTRACK_OK) {
      std::fprintf(stderr, "consumer: %s\n", handtrack::Client::describe(st).c_str());
    } else if (client.latest(out) == HANDTRACK_OK && out.frame == 5 && out.epoch == writer.epoch()) {
      std::puts("consumer_cpp ok");
      rc = 0;
    }
  }
  PoseRingWriter::remove(name);
  return rc;
}
