#pragma once
// Several hands at once (issue 14; the paper's future work, Sec. 8: "multiple hands interacting
// with each other"). Each hand is a Tracker of its own (its pose history, its choice of left or
// right hand), in a slot that keeps it while the hand stays in view; the frame's depth is shared
// out among the slots before any of them segments it, so no two hands ever fit the same pixels:
//
//   1. Connected surfaces of the working volume (neighbouring depths closer than continuity_mm).
//   2. A tracked hand claims the surfaces that come within `claim_mm` of its last pose's skeleton
//      (bones between its joints). A surface claimed by one hand is all its own (its forearm too,
//      so the wrist cut works as for one hand); the pixels of a surface claimed by several hands
//      (touching, clasped or clapping hands) go to the hand whose skeleton is nearest.
//   3. A free slot takes the nearest unclaimed surface that could be a hand (big enough, not a
//      body reaching in through the far plane, not the part of a body wider than any hand); a new
//      hand therefore appears only apart from the hands already tracked, and one that touches a
//      tracked hand waits until they part. So too with room for one hand.
//   4. Each slot's Tracker sees the frame with every pixel but its own marked foreign: never its
//      hand, but still depth (a hand behind the other is hidden there, not floating over nothing),
//      and fits it exactly as it fits a single hand.
//
// A slot whose Tracker finds no hand while another hand is seen (it may be hidden behind that one)
// keeps its id and last pose, unreported, for TrackerConfig::hidden_hand_frames frames, and looks
// for the hand where it was last seen: when it shows again near there it is the same hand. A hand
// that finds no fit with no other hand in view, or stays away longer, has left: its slot is freed
// and its id never given out again, so a hand that comes back has a fresh id and a fresh start.
// Where two hands are fitted the other hand's last pose is an obstacle for each
// (EnergyFrame::other_hand, E_col between the hands).
//
// Threading: like Tracker, request() / begin() / finish() on one thread; fit(slot) of different
// slots may run on different threads at once between begin() and finish() (the slots share no
// mutable state: HandsTracker's own state is written only by begin() and finish()).
// HandsInputs::build() anywhere, on inputs no fit reads at the time.

#include "handtrack/core/energy.hpp"
#include "handtrack/core/kinematics.hpp"
#include "handtrack/core/tracker.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>

namespace handtrack {

// The most hands a frame can have (TrackerConfig::max_hands is clamped to it; the shared-memory
// record has room for as many: HANDTRACK_MAX_HANDS).
inline constexpr int kMaxHands = 2;

// What the next frame's preprocessing needs: per slot, whether it holds a hand, that hand's
// request (which of left / right, the segmentation hints) and where it was (for sharing out the
// pixels).
struct HandsRequest {
  int max_hands = 1;
  struct Slot {
    bool active = false;  // tracks a hand; else free for a new one
    InputRequest request;
    Joints joints{};      // last pose, camera frame (active slots)
  };
  std::array<Slot, kMaxHands> slots{};
  // Where a new surface was lately found to be no hand (its centroid, camera frame): not tried
  // again there for TrackerConfig::new_hand_retry_frames frames (a full (re)start costs 20-100 ms).
  std::array<Eigen::Vector3d, kMaxHands> rejected{};
  int rejected_count = 0;
};

class HandSplitter;  // core/src: steps 1-3 above

// What a slot gets of a frame.
enum class FrameShare : uint8_t {
  kNothing,  // a free slot with no new surface
  kWhole,    // the whole frame: the only hand to fit, and no other sizeable surface to tell apart
             // (exactly what a Tracker alone sees, so the hand is tracked as by one)
  kOwn,      // its own pixels, the rest 0 (an active slot's maybe none)
};

// The scratch of sharing a frame out among the slots (steps 1-3 above: the median filter, the
// surfaces and their claims, a few full-frame buffers), needed from HandsInputs::share() until the
// frame's slots are built. A HandsInputs owns one, or borrows one that several share: handtrackd's
// pool of frames is shared out one frame at a time, so one serves them all (640x480 depth: the
// daemon's resident memory 117 -> 53 MB).
class FrameSplitter {
 public:
  FrameSplitter();
  ~FrameSplitter();
  FrameSplitter(const FrameSplitter&) = delete;
  FrameSplitter& operator=(const FrameSplitter&) = delete;

 private:
  friend class HandsInputs;
  std::unique_ptr<HandSplitter> splitter_;
};

// One frame's inputs for every slot. Storage is reused between frames (a pipeline keeps one per
// frame in flight).
class HandsInputs {
 public:
  explicit HandsInputs(const DepthInputConfig& config = {});
  // Borrows `splitter`, which must outlive it. Of the HandsInputs that borrow one splitter, one at a
  // time shares a frame out and builds its slots (share() to the last build_slot()).
  HandsInputs(const DepthInputConfig& config, FrameSplitter& splitter);
  ~HandsInputs();
  HandsInputs(HandsInputs&&) noexcept;
  HandsInputs& operator=(HandsInputs&&) noexcept;

  void build(const DepthImage& depth, const HandsRequest& request, const PixelLabeller* labeller = nullptr);
  // build() in two steps, for a caller that builds the slots on several threads: share() shares the
  // frame out and says which slots to build (a bit per slot); build_slot(i) of different slots may
  // then run at once (`depth` and `request` as given to share(), unchanged until they return).
  uint32_t share(const DepthImage& depth, const HandsRequest& request);
  void build_slot(int slot, const DepthImage& depth, const HandsRequest& request, const PixelLabeller* labeller);
  // Whether slot `i` has an input this frame: the pixels of the hand it tracks, or a surface that
  // may be a new hand (a free slot).
  [[nodiscard]] bool has(int slot) const { return has_[static_cast<size_t>(slot)]; }
  [[nodiscard]] const TrackerInputs& slot(int i) const { return inputs_[static_cast<size_t>(i)]; }
  // A free slot's new surface: its centroid (camera frame, mm).
  [[nodiscard]] const std::optional<Eigen::Vector3d>& candidate(int i) const {
    return candidate_[static_cast<size_t>(i)];
  }

 private:
  DepthInputConfig config_;
  std::unique_ptr<FrameSplitter> own_splitter_;  // null when borrowed
  HandSplitter* splitter_;                       // own_splitter_'s or the borrowed one's
  std::array<std::vector<uint8_t>, kMaxHands> foreign_{};  // kOwn slots: 1 = not the slot's pixel
  std::array<TrackerInputs, kMaxHands> inputs_;
  std::array<bool, kMaxHands> has_{};
  std::array<FrameShare, kMaxHands> share_{};
  std::array<std::optional<Eigen::Vector3d>, kMaxHands> candidate_{};
};

// One frame's hands, in slot order (not sorted by id); count of them valid.
struct HandsOutput {
  int count = 0;
  std::array<TrackerOutput, kMaxHands> hands{};
  std::array<double, kMaxHands> optimize_ms{};  // each hand's fit (wall clock of its thread)
  std::array<int, kMaxHands> slot{};            // each hand's slot (HandsTracker::slot_tracker, HandsInputs::slot)
};

class HandsTracker {
 public:
  explicit HandsTracker(const TrackerConfig& config = {});

  [[nodiscard]] HandsRequest request() const;
  // A frame in three steps, for a caller that fits the slots on several threads: begin() says
  // which slots to fit (a bit per slot), fit(i) fits one, finish() gives the frame's hands.
  uint32_t begin(const HandsInputs& inputs);
  void fit(int slot, const HandsInputs& inputs);
  HandsOutput finish();
  // All three on this thread.
  HandsOutput optimise(const HandsInputs& inputs);
  // Preprocessing and optimise() on this thread: what handtrack-eval uses.
  HandsOutput track(const DepthImage& depth, const PixelLabeller* labeller = nullptr);
  [[nodiscard]] const HandsInputs& last_inputs() const { return inputs_; }
  [[nodiscard]] Tracker& slot_tracker(int slot) { return slots_[static_cast<size_t>(slot)].tracker; }
  [[nodiscard]] const TrackerConfig& config() const { return config_; }
  [[nodiscard]] int max_hands() const { return max_hands_; }
  void reset();

 private:
  struct Slot {
    Tracker tracker;
    TrackerOutput last;      // last frame's output (state kNoHand: the slot is free)
    TrackerOutput current;   // this frame's, written by fit()
    double optimize_ms = 0.0;
    uint32_t id = 0;         // handtrack's hand id, 0 while free
    int hidden_frames = 0;   // frames in a row without a fit while holding an id
    // Its side has been clear (handedness_confidence >= TrackerConfig::handedness_margin) in some
    // frame since it appeared: its first handedness trial has ended.
    bool side_told = false;
    std::optional<Eigen::Vector3d> trying;  // a free slot's new surface this frame
    // The other hand's last pose, as this slot's right-hand tracker sees it and as its left-hand
    // tracker does (begin()).
    std::array<HandObstacle, 2> other;
  };
  // The other slot's hand when it was seen in the last frame (not free, not hidden), else null.
  [[nodiscard]] const Slot* other_seen(int slot) const;
  // Each slot's view of the other hand seen in the last frame: the side it expects to be not
  // (Tracker::expect) and, for a slot fitted this frame, the other hand's pose as an obstacle.
  void face_other_hands();
  struct Rejected {
    Eigen::Vector3d centre;
    int frames_left = 0;
  };
  TrackerConfig config_;
  int max_hands_ = 1;
  std::array<Slot, kMaxHands> slots_;
  uint32_t fitting_ = 0;  // begin()'s bits
  uint32_t last_id_ = 0;
  std::array<Rejected, kMaxHands> rejected_{};
  int rejected_count_ = 0;
  HandsInputs inputs_;    // track()'s
  PosedHand posed_;       // face_other_hands()' scratch
};

}  // namespace handtrack
