// The pose filter of the C API (handtrack/client.h, handtrack_filter_*): a One Euro filter
// (one_euro.hpp) on every point of every hand of a frame, each hand followed by its hand_id and
// reset where its sequence of poses breaks.
#include "hand_slots.hpp"
#include "one_euro.hpp"

#include <handtrack/client.h>

#include <array>
#include <cmath>
#include <new>

namespace {

using handtrack::ipc::detail::OneEuroParams;
using handtrack::ipc::detail::OneEuroPoint;

// The filter of one hand: its points and where its sequence of poses stands (HandFilter{}: afresh).
struct HandFilter {
  uint32_t hand_id = 0;  // 0: free
  std::array<OneEuroPoint, HANDTRACK_NUM_JOINTS> joints;
  std::array<OneEuroPoint, HANDTRACK_NUM_FINGERTIPS> tips;
  OneEuroPoint palm_center;
  OneEuroPoint palm_normal;
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

  void apply(handtrack_hand& hand, uint64_t frame_epoch, int64_t capture_ns, const handtrack_filter_params& params,
             const OneEuroParams& euro) noexcept {
    const double dt_s = primed ? static_cast<double>(capture_ns - last_capture_ns) * 1e-9 : 0.0;
    // A new writer, a gap, time going backwards or no tracked hand: start afresh (the hand passes
    // through unchanged, and the next tracked pose primes the filter).
    if (!primed || frame_epoch != epoch || dt_s <= 0.0 || dt_s > params.max_gap_s ||
        hand.state != HANDTRACK_STATE_TRACKING) {
      reset();
    }
    if (hand.state != HANDTRACK_STATE_TRACKING) return;
    for (int j = 0; j < HANDTRACK_NUM_JOINTS; ++j) joints[j].filter(hand.joints_mm[j], dt_s, euro);
    for (int t = 0; t < HANDTRACK_NUM_FINGERTIPS; ++t) tips[t].filter(hand.fingertips_mm[t], dt_s, euro);
    palm_center.filter(hand.palm_center_mm, dt_s, euro);
    palm_normal.filter(hand.palm_normal, dt_s, euro);
    const float n = std::sqrt(hand.palm_normal[0] * hand.palm_normal[0] + hand.palm_normal[1] * hand.palm_normal[1] +
                              hand.palm_normal[2] * hand.palm_normal[2]);
    if (n > 0.0F) {
      for (float& c : hand.palm_normal) c /= n;
    }
    primed = true;
    epoch = frame_epoch;
    last_capture_ns = capture_ns;
  }
};

}  // namespace

// One HandFilter per hand a frame can hold, matched to the frame's hands by hand_id.
struct handtrack_filter {
  handtrack_filter_params params{};
  OneEuroParams euro{};
  std::array<HandFilter, HANDTRACK_MAX_HANDS> hands;

  void reset() noexcept { hands.fill(HandFilter{}); }

  void apply(handtrack_frame& frame) noexcept {
    using handtrack::ipc::detail::frame_has_hand;
    // A hand missing from this frame has left: its history goes (a returning hand gets a new id).
    for (HandFilter& h : hands) {
      if (h.hand_id != 0 && !frame_has_hand(frame, h.hand_id)) h = HandFilter{};
    }
    const uint32_t count = handtrack::ipc::detail::hand_count(frame);
    for (uint32_t i = 0; i < count; ++i) {
      handtrack_hand& hand = frame.hands[i];
      if (hand.hand_id == 0) continue;  // not a hand (a present hand never has id 0)
      handtrack::ipc::detail::hand_state(hands, hand.hand_id).apply(hand, frame.epoch, frame.capture_ns, params, euro);
    }
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

int handtrack_filter_apply(handtrack_filter* filter, handtrack_frame* frame) {
  if (filter == nullptr || frame == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  filter->apply(*frame);
  return HANDTRACK_OK;
}

}  // extern "C"
