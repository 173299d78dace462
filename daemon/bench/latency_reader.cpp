// handtrack-latency: how old a pose is when a client gets it. For N records read with
// handtrack_wait_next it measures, on CLOCK_MONOTONIC (the clock of capture_ns and publish_ns):
//   pipeline = publish_ns - capture_ns      (the daemon: grab, queues, preprocess, optimize, publish)
//   wake     = read time - publish_ns       (the futex wake-up and the seqlock copy in the client)
//   total    = read time - capture_ns       (frame in to pose readable)
// and prints p50/p99/max of each as one JSON object. --trace FILE also writes one CSV row per
// record (its stage and per-hand times), to see which frames make the tail.
#include <handtrack/client.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

namespace {

int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  return v[k];
}

std::string summary(const char* name, const std::vector<double>& v) {
  char text[160];
  std::snprintf(text, sizeof text, "\"%s\":{\"p50\":%.3f,\"p99\":%.3f,\"max\":%.3f}", name, quantile(v, 0.5),
                quantile(v, 0.99), v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()));
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Measure how old poses are when a client reads them (p50/p99 in ms, JSON)."};
  std::string shm_name = HANDTRACK_DEFAULT_SHM_NAME;
  int count = 600;
  int skip = 60;
  double timeout_s = 10.0;
  std::string trace_path;
  app.add_option("--shm-name", shm_name, "shared-memory object name")->capture_default_str();
  app.add_option("--count", count, "records to measure")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--skip", skip, "records to ignore first (warm-up)")->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--timeout", timeout_s, "give up after S seconds without a record")->capture_default_str();
  app.add_option("--trace", trace_path, "also write one CSV row per measured record to this file");
  CLI11_PARSE(app, argc, argv);
  std::FILE* trace = nullptr;
  if (!trace_path.empty()) {
    trace = std::fopen(trace_path.c_str(), "w");
    if (trace == nullptr) {
      std::perror(("handtrack-latency: " + trace_path).c_str());
      return 1;
    }
    std::fprintf(trace, "frame,hands,preprocess_ms,optimize_ms,hand0_optimize_ms,hand1_optimize_ms,"
                        "pipeline_ms,wake_ms,total_ms\n");
  }

  handtrack::Client client;
  const int64_t open_deadline = now_ns() + static_cast<int64_t>(timeout_s * 1e9);
  int st = client.open(shm_name);
  while (st != HANDTRACK_OK && now_ns() < open_deadline) {
    timespec pause{0, 20'000'000};
    nanosleep(&pause, nullptr);
    st = client.open(shm_name);
  }
  if (st != HANDTRACK_OK) {
    std::fprintf(stderr, "handtrack-latency: %s\n", handtrack::Client::describe(st).c_str());
    return 1;
  }
  std::vector<double> pipeline, wake, total;
  handtrack_frame frame{};
  int seen = 0;
  while (static_cast<int>(total.size()) < count) {
    st = client.wait_next(frame, std::chrono::nanoseconds(static_cast<int64_t>(timeout_s * 1e9)));
    const int64_t read_ns = now_ns();
    if ((st == HANDTRACK_ERR_WRITER_STOPPED || st == HANDTRACK_ERR_WRITER_DEAD || st == HANDTRACK_TIMEOUT) &&
        seen == 0 && read_ns < open_deadline + static_cast<int64_t>(timeout_s * 1e9)) {
      continue;  // an earlier daemon's segment: the client reattaches to the new writer by itself
    }
    if (st != HANDTRACK_OK) {
      std::fprintf(stderr, "handtrack-latency: after %zu records: %s\n", total.size(), handtrack_strerror(st));
      return 1;
    }
    if (seen++ < skip) continue;
    pipeline.push_back(static_cast<double>(frame.publish_ns - frame.capture_ns) * 1e-6);
    wake.push_back(static_cast<double>(read_ns - frame.publish_ns) * 1e-6);
    total.push_back(static_cast<double>(read_ns - frame.capture_ns) * 1e-6);
    if (trace != nullptr) {
      std::fprintf(trace, "%llu,%u,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", static_cast<unsigned long long>(frame.frame),
                   frame.hand_count, frame.preprocess_ms, frame.optimize_ms,
                   frame.hand_count > 0 ? frame.hands[0].optimize_ms : 0.0F,
                   frame.hand_count > 1 ? frame.hands[1].optimize_ms : 0.0F, pipeline.back(), wake.back(), total.back());
    }
  }
  if (trace != nullptr) std::fclose(trace);
  std::printf("{\"records\":%zu,\"missed\":%llu,%s,%s,%s}\n", total.size(),
              static_cast<unsigned long long>(client.missed_total()), summary("pipeline_ms", pipeline).c_str(),
              summary("wake_ms", wake).c_str(), summary("total_ms", total).c_str());
  return 0;
}
