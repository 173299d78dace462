// HandsTracker: several hands, each a Tracker in a slot, on their own share of the frame
// (hand_splitter.hpp).
#include "handtrack/core/hands_tracker.hpp"

#include "hand_splitter.hpp"

#include <algorithm>
#include <chrono>

namespace handtrack {

FrameSplitter::FrameSplitter() : splitter_(std::make_unique<HandSplitter>()) {}
FrameSplitter::~FrameSplitter() = default;

static_assert(kMaxHands == 2, "HandsInputs::inputs_ lists one TrackerInputs per hand");

HandsInputs::HandsInputs(const DepthInputConfig& config)
    : config_(config),
      own_splitter_(std::make_unique<FrameSplitter>()),
      splitter_(own_splitter_->splitter_.get()),
      inputs_{TrackerInputs(config), TrackerInputs(config)} {}

HandsInputs::HandsInputs(const DepthInputConfig& config, FrameSplitter& splitter)
    : config_(config), splitter_(splitter.splitter_.get()), inputs_{TrackerInputs(config), TrackerInputs(config)} {}

HandsInputs::~HandsInputs() = default;
HandsInputs::HandsInputs(HandsInputs&&) noexcept = default;
HandsInputs& HandsInputs::operator=(HandsInputs&&) noexcept = default;

void HandsInputs::build(const DepthImage& depth, const HandsRequest& request, const PixelLabeller* labeller) {
  const uint32_t slots = share(depth, request);
  for (int s = 0; s < kMaxHands; ++s) {
    if ((slots & (1U << static_cast<unsigned>(s))) != 0) build_slot(s, depth, request, labeller);
  }
}

uint32_t HandsInputs::share(const DepthImage& depth, const HandsRequest& request) {
  // The splitter shares the frame out for one hand too: a tracked hand gets its own surfaces when
  // something else sizeable is in the volume (a body, its head), the whole frame when not (then
  // exactly as a Tracker alone sees it), and a free slot is not given a surface found to be no hand
  // again and again (HandsRequest::rejected).
  splitter_->split(config_, depth, request, foreign_, share_, candidate_);
  uint32_t slots = 0;
  for (size_t s = 0; s < kMaxHands; ++s) {
    has_[s] = share_[s] != FrameShare::kNothing;
    if (has_[s]) slots |= 1U << s;
  }
  return slots;
}

void HandsInputs::build_slot(int slot, const DepthImage& depth, const HandsRequest& request,
                             const PixelLabeller* labeller) {
  const auto s = static_cast<size_t>(slot);
  // The splitter's median filter is every slot's.
  inputs_[s].build(depth, request.slots[s].request, labeller, share_[s] == FrameShare::kWhole ? nullptr : &foreign_[s],
                   &splitter_->median());
}

HandsTracker::HandsTracker(const TrackerConfig& config)
    : config_(config), max_hands_(std::clamp(config.max_hands, 1, kMaxHands)), inputs_(input_config(config)) {
  for (size_t s = 0; s < slots_.size(); ++s) {
    TrackerConfig c = config;
    c.seed = config.seed + s;  // each hand its own particles
    slots_[s].tracker = Tracker(c);
  }
}

void HandsTracker::reset() {
  for (Slot& s : slots_) {
    s.tracker.reset();
    s.last = TrackerOutput{};
    s.current = TrackerOutput{};
    s.id = 0;
    s.hidden_frames = 0;
    s.side_told = false;
  }
  rejected_count_ = 0;
}

HandsRequest HandsTracker::request() const {
  HandsRequest r;
  r.max_hands = max_hands_;
  for (int s = 0; s < max_hands_; ++s) {
    const Slot& slot = slots_[static_cast<size_t>(s)];
    auto& out = r.slots[static_cast<size_t>(s)];
    out.active = slot.id != 0;
    out.request = slot.tracker.request();
    out.joints = slot.last.joints;
  }
  r.rejected_count = rejected_count_;
  for (int k = 0; k < rejected_count_; ++k) r.rejected[static_cast<size_t>(k)] = rejected_[static_cast<size_t>(k)].centre;
  return r;
}

uint32_t HandsTracker::begin(const HandsInputs& inputs) {
  fitting_ = 0;
  for (int s = 0; s < max_hands_; ++s) {
    Slot& slot = slots_[static_cast<size_t>(s)];
    slot.current = TrackerOutput{};
    slot.optimize_ms = 0.0;
    slot.trying = slot.id == 0 ? inputs.candidate(s) : std::nullopt;
    if (inputs.has(s)) fitting_ |= 1U << static_cast<unsigned>(s);
  }
  face_other_hands();
  return fitting_;
}

const HandsTracker::Slot* HandsTracker::other_seen(int s) const {
  for (int o = 0; o < max_hands_; ++o) {
    const Slot& other = slots_[static_cast<size_t>(o)];
    if (o != s && other.id != 0 && other.hidden_frames == 0) return &other;  // a hidden hand's pose is old
  }
  return nullptr;
}

void HandsTracker::face_other_hands() {
  for (int s = 0; s < max_hands_; ++s) {
    Slot& slot = slots_[static_cast<size_t>(s)];
    slot.tracker.set_other_hand(nullptr, nullptr);
    slot.tracker.expect(std::nullopt);
    const Slot* other = other_seen(s);
    if (other == nullptr) continue;
    // Two hands in one frame are usually a left and a right one: the slot expects to be the hand
    // the other is not (it decides choices between left and right that its fits leave open, and,
    // where the other hand's side is the clearer of the two, those they do not make clear).
    //
    // Until either hand's side has been told (both still in their first trial: flat hands side-on
    // to the camera, clapping), following the other is following a coin flip: whichever hand's
    // evidence first strays from the tie takes a side, the other the opposite, and in two_clap both
    // were wrong in up to 45 % of the frames. Then the hand further left in the image is expected
    // to be the right hand, as a camera facing the user sees them (the assumption of the lone
    // hand's palm-toward rule, Tracker::weigh), and the hand further right for a head-mounted
    // camera (TrackerConfig::arrangement), for every choice its evidence does not make clear
    // (docs/TRACKER.md, "Two hands": "A pair not yet told apart").
    const bool other_left = other->last.handedness == Handedness::kLeft;
    if (slot.id != 0 && !slot.side_told && !other->side_told) {
      const auto image_x = [](const TrackerOutput& o) { return o.palm_centre.x() / o.palm_centre.z(); };
      const bool image_left = image_x(slot.last) < image_x(other->last);
      const bool right = image_left == (config_.arrangement == CameraArrangement::kFacing);
      slot.tracker.expect(right ? Handedness::kRight : Handedness::kLeft, config_.handedness_margin);
    } else {
      slot.tracker.expect(other_left ? Handedness::kRight : Handedness::kLeft, other->last.handedness_confidence);
    }
    if ((fitting_ & (1U << static_cast<unsigned>(s))) == 0) continue;
    // The other hand's last params are the right-hand model's, in the mirrored image for a left
    // hand: posed as they are, its Gaussians are in the camera frame after mirroring x exactly when
    // it is a left hand; a left-hand tracker of this slot wants them mirrored once more.
    posed_.update(other->tracker.model(), other->last.params);
    slot.other[0].assign(other->tracker.model(), posed_, other_left);
    slot.other[1].assign(other->tracker.model(), posed_, !other_left);
    slot.tracker.set_other_hand(&slot.other[0], &slot.other[1]);
  }
}

void HandsTracker::fit(int s, const HandsInputs& inputs) {
  Slot& slot = slots_[static_cast<size_t>(s)];
  const auto start = std::chrono::steady_clock::now();
  slot.current = slot.tracker.optimise(inputs.slot(s));
  slot.optimize_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

HandsOutput HandsTracker::finish() {
  // Places found to be no hand are forgotten after new_hand_retry_frames frames.
  int kept = 0;
  for (int k = 0; k < rejected_count_; ++k) {
    Rejected r = rejected_[static_cast<size_t>(k)];
    if (--r.frames_left > 0) rejected_[static_cast<size_t>(kept++)] = r;
  }
  rejected_count_ = kept;

  // How many hands were fitted this frame: a hand that finds no fit while another one is seen may be
  // hidden behind it; alone, it has left.
  int seen = 0;
  for (int s = 0; s < max_hands_; ++s) {
    const bool fitted = (fitting_ & (1U << static_cast<unsigned>(s))) != 0;
    seen += fitted && slots_[static_cast<size_t>(s)].current.state != TrackingState::kNoHand ? 1 : 0;
  }
  HandsOutput out;
  for (int s = 0; s < max_hands_; ++s) {
    Slot& slot = slots_[static_cast<size_t>(s)];
    if ((fitting_ & (1U << static_cast<unsigned>(s))) == 0) continue;
    if (slot.current.state == TrackingState::kNoHand) {
      if (slot.id != 0 && seen > 0 && ++slot.hidden_frames <= config_.hidden_hand_frames) {
        // Hidden: keeps its id, and looks for the hand where it was last seen (a (re)start on the
        // few pixels of a half-hidden hand fits it poorly, and costs 16 ms a frame).
        slot.tracker.resume(slot.last);
        continue;
      }
      // Gone (or never a hand): the slot is free and its id retired.
      if (slot.trying && rejected_count_ < static_cast<int>(rejected_.size())) {
        rejected_[static_cast<size_t>(rejected_count_++)] = {*slot.trying, config_.new_hand_retry_frames};
      }
      slot.id = 0;
      slot.hidden_frames = 0;
      slot.side_told = false;
      slot.tracker.reset();
      slot.last = TrackerOutput{};
      continue;
    }
    slot.hidden_frames = 0;
    if (slot.id == 0) slot.id = ++last_id_;
    slot.current.hand_id = slot.id;
    slot.side_told = slot.side_told || slot.current.handedness_confidence >= config_.handedness_margin;
    slot.last = slot.current;
    out.hands[static_cast<size_t>(out.count)] = slot.current;
    out.optimize_ms[static_cast<size_t>(out.count)] = slot.optimize_ms;
    out.slot[static_cast<size_t>(out.count)] = s;
    ++out.count;
  }
  // Both hands chosen as the same hand: the less clear choice is made again at the next frame.
  if (out.count == 2 && out.hands[0].handedness == out.hands[1].handedness) {
    const int doubtful = out.hands[0].handedness_confidence <= out.hands[1].handedness_confidence ? 0 : 1;
    slots_[static_cast<size_t>(out.slot[static_cast<size_t>(doubtful)])].tracker.question_handedness();
  }
  return out;
}

HandsOutput HandsTracker::optimise(const HandsInputs& inputs) {
  const uint32_t fitting = begin(inputs);
  for (int s = 0; s < kMaxHands; ++s) {
    if ((fitting & (1U << static_cast<unsigned>(s))) != 0) fit(s, inputs);
  }
  return finish();
}

HandsOutput HandsTracker::track(const DepthImage& depth, const PixelLabeller* labeller) {
  inputs_.build(depth, request(), labeller);
  return optimise(inputs_);
}

}  // namespace handtrack
