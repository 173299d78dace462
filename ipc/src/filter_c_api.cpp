// The pose filter of the C API (handtrack/client.h, handtrack_filter_*): a One Euro filter
// (one_euro.hpp) on every point of a pose, reset where the pose sequence breaks.
#include "one_euro.hpp"

#include <handtrack/client.h>

#include <array>
#include <cmath>
#include <new>

struct handtrack_filter {
  handtrack_filter_params params{};
  handtrack::ipc::detail::OneEuroParams euro{};
  std::array<handtrack::ipc::detail::OneEuroPoint, HANDTRACK_NUM_JOINTS> joints;
  std::array<handtrack::ipc::detail::OneEuroPoint, HANDTRACK_NUM_FINGERTIPS> tips;
  handtrack::ipc::detail::OneEuroPoint palm_center;
  handtrack::ipc::detail::OneEuroPoint palm_normal;
  bool primed = false;
  uint64_t epoch = 0;
  int64_t last_capture_ns = 0;

  void reset() noexcept {
    for (auto& p : joints) p.reset();
    for (auto& p : tips) p.reset();
    palm_center.reset();
    palm_normal.reset();
    primed = false;
  }

  void apply(handtrack_pose& pose) noexcept {
    const double dt_s = primed ? static_cast<double>(pose.capture_ns - last_capture_ns) * 1e-9 : 0.0;
    // A new writer, a gap, time going backwards or no tracked hand: start afresh (the pose passes
    // through unchanged, and the next tracked pose primes the filter).
    if (!primed || pose.epoch != epoch || dt_s <= 0.0 || dt_s > params.max_gap_s ||
        pose.state != HANDTRACK_STATE_TRACKING) {
      reset();
    }
    if (pose.state != HANDTRACK_STATE_TRACKING) return;
    for (int j = 0; j < HANDTRACK_NUM_JOINTS; ++j) joints[j].filter(pose.joints_mm[j], dt_s, euro);
    for (int t = 0; t < HANDTRACK_NUM_FINGERTIPS; ++t) tips[t].filter(pose.fingertips_mm[t], dt_s, euro);
    palm_center.filter(pose.palm_center_mm, dt_s, euro);
    palm_normal.filter(pose.palm_normal, dt_s, euro);
    const float n = std::sqrt(pose.palm_normal[0] * pose.palm_normal[0] + pose.palm_normal[1] * pose.palm_normal[1] +
                              pose.palm_normal[2] * pose.palm_normal[2]);
    if (n > 0.0F) {
      for (float& c : pose.palm_normal) c /= n;
    }
    primed = true;
    epoch = pose.epoch;
    last_capture_ns = pose.capture_ns;
  }
};

namespace {

bool valid(const handtrack_filter_params& p) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  return positive(p.min_cutoff_hz) && positive(p.d_cutoff_hz) && positive(p.max_gap_s) && std::isfinite(p.beta) &&
         p.beta >= 0.0;
}

}  // namespace

extern "C" {

void handtrack_filter_default_params(handtrack_filter_params* out) {
  if (out == nullptr) return;
  out->min_cutoff_hz = HANDTRACK_FILTER_DEFAULT_MIN_CUTOFF_HZ;
  out->beta = HANDTRACK_FILTER_DEFAULT_BETA;
  out->d_cutoff_hz = HANDTRACK_FILTER_DEFAULT_D_CUTOFF_HZ;
  out->max_gap_s = HANDTRACK_FILTER_DEFAULT_MAX_GAP_S;
}

int handtrack_filter_new(const handtrack_filter_params* params, handtrack_filter** out) {
  if (out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  *out = nullptr;
  handtrack_filter_params p;
  handtrack_filter_default_params(&p);
  if (params != nullptr) p = *params;
  if (!valid(p)) return HANDTRACK_ERR_INVALID_ARGUMENT;
  auto* filter = new (std::nothrow) handtrack_filter;
  if (filter == nullptr) return HANDTRACK_ERR_SYSTEM;
  filter->params = p;
  filter->euro = {p.min_cutoff_hz, p.beta, p.d_cutoff_hz};
  *out = filter;
  return HANDTRACK_OK;
}

void handtrack_filter_free(handtrack_filter* filter) { delete filter; }

void handtrack_filter_reset(handtrack_filter* filter) {
  if (filter != nullptr) filter->reset();
}

int handtrack_filter_apply(handtrack_filter* filter, handtrack_pose* pose) {
  if (filter == nullptr || pose == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  filter->apply(*pose);
  return HANDTRACK_OK;
}

}  // extern "C"
