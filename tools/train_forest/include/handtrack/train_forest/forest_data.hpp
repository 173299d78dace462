#pragma once
// Labelled synthetic training and test data for the part forest (Sec. 4.3), and its evaluation.
//
// A scene is a pure function of (seed, index): a random subject (length and width within +-10 %),
// background (body, table or none), sensor noise, and either a random pose within
// JointLimits::defaults() placed at 250-550 mm with a random global rotation, or a frame of one of
// the seven motion scripts. The frame goes through DepthInputBuilder with no hint, exactly as the
// tracker sees a frame without a previous pose; the hand mask's pixels get the synthetic label
// image's part (0 = background class for the forearm and anything else the mask kept).

#include "handtrack/core/camera.hpp"
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace handtrack::forest {

// Probes off the hand read this depth (mm) during training; stored in the model header.
inline constexpr float kBackgroundDepthMm = 4000.0F;

// The hand pixels of one frame, cropped to the hand mask's bounding box.
struct LabelledImage {
  int width = 0;   // crop size
  int height = 0;
  std::vector<float> depth_mm;  // filtered depth on the mask, kBackgroundDepthMm elsewhere
  std::vector<uint8_t> labels;  // class 0..12 on the mask, kOffMask elsewhere
  int hand_pixels = 0;
  InPlaneTurn turn;  // hand_turn() of the segmentation's unhinted axis: a hand-aligned forest's probes
  static constexpr uint8_t kOffMask = 255;
};

struct SceneOptions {
  double motion_fraction = 0.3;     // share of frames taken from the motion scripts, the rest random poses
  double near_mm = 250.0;           // palm centre depth range of the random poses
  double far_mm = 550.0;
  double volume_far_mm = 600.0;     // far end of the working volume the training frames are segmented in
  double max_roll_deg = 90.0;       // random poses: rotation about the camera's viewing axis
  double max_pitch_deg = 50.0;      // ... about the camera x axis (tilt toward / away)
  double max_yaw_deg = 60.0;        // ... about the camera y axis
  // Share of the random poses turned any way instead (issue "Every hand, every view"): the back or
  // a side toward the camera (yaw up to 180 deg), fingers toward or away from it (pitch up to
  // kMaxTurnedPitchDeg), any roll.
  double turned_fraction = 0.5;
  // Share of the motion frames seen in another view than palm (synth/views.hpp: back, side, fingers
  // toward or away, head-mounted), drawn uniformly among them.
  double view_fraction = 0.5;
  // Share of the images with a ball held against the palm (radius kMinTrainingHeldRadiusMm..
  // kMaxTrainingHeldRadiusMm; synth --ball): its pixels that segmentation keeps with the hand are
  // background (label 0) to learn, so that the tracker can drop them
  // (DepthInputConfig::drop_background). Drawn after everything else in a scene, so 0 leaves the
  // data set of the forests trained before it unchanged.
  double ball_fraction = 0.0;
  // Of those held objects, the share that are bottles instead of balls (synth --bottle: a capsule of
  // the same radius across the palm). Drawn from a stream of its own, so 0 leaves the data set
  // unchanged (docs/TRACKER.md, "A held object").
  double bottle_share = 0.0;
  // Share of the images that show what a free hand slot is given besides the hand when the body is
  // inside the working volume (synth --background near-body, not with the head-mounted view): the
  // surface segmentation takes once the hand and its forearm are gone (a head, the rest of a
  // torso), all of it background (label 0) to learn, so that the tracker drops it instead of
  // fitting a hand to it. Drawn last, so 0 leaves the data set unchanged.
  double body_fraction = 0.0;
  // Share of the images whose hand has varied proportions (synth::Proportions::kVaried: every
  // finger's length, the fingers' girth and the palm's thickness drawn beside the subject's size).
  // Drawn from a stream of its own, so 0 leaves the data set unchanged.
  double varied_fraction = 0.0;
  // The motion images moved along their palm ray by a depth offset drawn uniformly from
  // [-spread, spread] mm (synth --depth-offset): the motions hold the palm 350-520 mm away, the
  // random poses 250-far_mm. Drawn from a stream of its own, so 0 leaves the data set unchanged
  // (docs/TRACKER.md, "Hands nearer and farther").
  double distance_spread_mm = 0.0;
  // The offset drawn from [0, spread] instead: the motion images moved farther only (the hands the
  // labels fail are the farther ones; docs/TRACKER.md, "Hands nearer and farther").
  bool distance_farther_only = false;
  // Share of the images whose hand is drawn without its arm, cut at the wrist (synth --arm none: a
  // renderer's hand model). Drawn from a stream of its own, so 0 leaves the data set unchanged
  // (docs/TRACKER.md, "A hand without its arm").
  double armless_fraction = 0.0;
  // Share of the motion images seen through a camera rolled about its axis by an angle drawn
  // uniformly from [-180, 180] deg (synth --roll): the forearm from any image edge. Drawn from a
  // stream of its own, so 0 leaves the data set unchanged (docs/TRACKER.md, "The forearm from any
  // image edge").
  double rolled_fraction = 0.0;
  CameraIntrinsics camera = synth::default_camera();
};

struct Scene {
  synth::SynthOptions options;  // subject, background, noise seed, motion
  bool from_motion = false;
  int frame = 0;
  synth::HandPose pose;  // what is rendered
  bool body = false;     // SceneOptions::body_fraction: the body without the hand is segmented
};

// The scene of image `index` of the data set `seed` (deterministic).
Scene make_scene(uint64_t seed, uint64_t index, const SceneOptions& options);
inline constexpr double kMaxTurnedPitchDeg = 80.0;

// A random pose within the joint limits, placed and rotated as `options` says.
synth::HandPose random_pose(synth::Rng& rng, const synth::HandShape& shape, const SceneOptions& options);

// Renders a scene and segments it as the tracker does (DepthInputBuilder with no hint).
struct RenderedScene {
  synth::SynthFrame frame;
  DepthInput input;  // copy of the builder's result
};
void render_scene(const Scene& scene, DepthInputBuilder& builder, RenderedScene& out);

// Crops the hand of a segmented frame: labels from `truth` (the synthetic label image).
LabelledImage crop_hand(const DepthInput& input, const std::vector<uint8_t>& truth);

// `count` labelled images of data set `seed` on `threads` threads; images whose hand has fewer
// than `min_hand_pixels` pixels are replaced by the next index beyond count (deterministically).
// `progress(done)` is called from the calling thread.
std::vector<LabelledImage> make_dataset(uint64_t seed, int count, const SceneOptions& options, int threads,
                                        int min_hand_pixels = 150,
                                        const std::function<void(int)>& progress = nullptr);

// Per-pixel confusion over hand-mask pixels: counts[truth][predicted].
struct Confusion {
  std::array<std::array<uint64_t, kPartForestClasses>, kPartForestClasses> counts{};
  void add(const Confusion& other);
  [[nodiscard]] uint64_t total() const;
  [[nodiscard]] double accuracy() const;            // all mask pixels (background class included)
  [[nodiscard]] double part_accuracy() const;       // only pixels whose truth is one of the 12 parts
  [[nodiscard]] double class_recall(int c) const;   // per class, NaN without pixels
  [[nodiscard]] std::string table() const;          // the 13 x 13 matrix as text, row = truth, % of row
};

// Labels the frame with the forest and compares with the truth on the hand mask.
Confusion score_frame(const PartForest& forest, const DepthInput& input, const std::vector<uint8_t>& truth,
                      std::vector<uint8_t>& scratch);

// Held-out synthetic frames: each of the seven motion scripts with its own random subject
// (seed = seed_base + motion index, backgrounds cycling body/table/none), `frames_per_motion`
// frames spread over a 241-frame sequence (training uses 300-frame sequences), seen in `view`, the
// subjects' hands of `proportions` (synth::Proportions).
struct HeldOutResult {
  std::array<Confusion, 7> per_motion;
  Confusion overall;
  int frames = 0;
};
HeldOutResult evaluate_motions(const PartForest& forest, uint64_t seed_base, int frames_per_motion,
                               synth::View view = synth::View::kPalm,
                               synth::Proportions proportions = synth::Proportions::kMean);
// Held-out random poses: the scenes of data set `seed` (use one never trained on), `count` frames.
Confusion evaluate_scenes(const PartForest& forest, uint64_t seed, int count, const SceneOptions& options);

}  // namespace handtrack::forest
