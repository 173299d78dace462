#include "handtrack/train_forest/forest_data.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <thread>

namespace handtrack::forest {
namespace {

constexpr uint64_t kSceneStream = 0xF0E57;  // Rng::stream purpose of the scene draws
constexpr uint64_t kProportionStream = 0x960B0;  // ... and of SceneOptions::varied_fraction's
constexpr uint64_t kDistanceStream = 0xD157;      // ... and of SceneOptions::distance_spread_mm's
constexpr uint64_t kArmStream = 0xA53;            // ... and of SceneOptions::armless_fraction's
constexpr uint64_t kRollStream = 0x5011;          // ... and of SceneOptions::rolled_fraction's
constexpr uint64_t kBottleStream = 0xB0771E;      // ... and of SceneOptions::bottle_share's
constexpr double kSubjectSpread = 0.10;      // subjects within +-10 % (as the synth's random subjects)
constexpr int kTrainingSequenceFrames = 300;  // motion frames are drawn from 300-frame sequences
constexpr int kHeldOutSequenceFrames = 241;   // held-out motions: other lengths, so other time samples
constexpr double kImageSpread = 0.25;         // palm centre within +-25 % of the image size of its centre
constexpr int kMaxSceneAttempts = 20;
// Radius of the held objects drawn: a golf ball to a large orange, bottles alike.
constexpr double kMinTrainingHeldRadiusMm = 20.0;
constexpr double kMaxTrainingHeldRadiusMm = 45.0;

constexpr std::array<synth::Background, 3> kBackgrounds = {synth::Background::kBody, synth::Background::kTable,
                                                           synth::Background::kNone};

double deg(double d) { return d * std::numbers::pi / 180.0; }

}  // namespace

synth::HandPose random_pose(synth::Rng& rng, const synth::HandShape& shape, const SceneOptions& options) {
  const synth::JointLimits limits = synth::JointLimits::defaults();
  synth::HandPose pose;
  // Half the hands flex their fingers together around one "grip" (fists, claws, open hands),
  // the other half draw every angle on its own: both within the joint limits.
  const bool coupled = rng.uniform() < 0.5;
  const double grip = rng.uniform();
  for (size_t f = 0; f < static_cast<size_t>(kNumFingers); ++f) {
    for (size_t k = 0; k < 4; ++k) {
      const double lo = limits.lower[f][k];
      const double hi = limits.upper[f][k];
      const double t = (coupled && k > 0) ? std::clamp(grip + 0.2 * rng.normal(), 0.0, 1.0) : rng.uniform();
      pose.fingers[f][k] = lo + t * (hi - lo);
    }
  }
  // Global rotation: roll about the viewing axis, then pitch and yaw out of the image plane, applied
  // to the rest orientation (palm toward the camera, fingers up): camera_R_hand = M R0. Yaw turns
  // the hand about its finger axis (180 deg: the back toward the camera), pitch tips the fingers
  // toward or away from the camera.
  const bool turned = rng.uniform() < options.turned_fraction;
  const double max_roll = turned ? 180.0 : options.max_roll_deg;
  const double max_pitch = turned ? kMaxTurnedPitchDeg : options.max_pitch_deg;
  const double max_yaw = turned ? 180.0 : options.max_yaw_deg;
  const Eigen::Matrix3d m = (Eigen::AngleAxisd(deg(rng.uniform(-max_roll, max_roll)), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(deg(rng.uniform(-max_pitch, max_pitch)), Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(deg(rng.uniform(-max_yaw, max_yaw)), Eigen::Vector3d::UnitY()))
                                .toRotationMatrix();
  const Eigen::AngleAxisd aa(m);
  pose.rotation = aa.angle() * aa.axis();
  // Palm centre at a random depth and image position; t is the wrist: t = p - R palm_centre_hand.
  const auto& cam = options.camera;
  const double z = rng.uniform(options.near_mm, options.far_mm);
  const double u = cam.cx + rng.uniform(-kImageSpread, kImageSpread) * cam.width;
  const double v = cam.cy + rng.uniform(-kImageSpread, kImageSpread) * cam.height;
  const Eigen::Vector3d palm = cam.unproject(u, v, z);
  pose.translation_mm = palm - synth::camera_R_hand(pose.rotation) * shape.palm_centre_mm;
  return pose;
}

Scene make_scene(uint64_t seed, uint64_t index, const SceneOptions& options) {
  synth::Rng rng = synth::Rng::stream(seed, index, kSceneStream);
  Scene s;
  s.options.seed = rng.next();
  s.options.subject = synth::SubjectScale{rng.uniform(1.0 - kSubjectSpread, 1.0 + kSubjectSpread),
                                          rng.uniform(1.0 - kSubjectSpread, 1.0 + kSubjectSpread)};
  s.options.background = kBackgrounds[rng.next() % kBackgrounds.size()];
  s.options.camera = options.camera;
  s.options.noise = true;
  s.options.frames = kTrainingSequenceFrames;
  if (rng.uniform() < options.motion_fraction) {
    s.from_motion = true;
    s.options.motion = std::string(synth::kMotionNames[rng.next() % synth::kMotionNames.size()]);
    s.frame = static_cast<int>(rng.next() % kTrainingSequenceFrames);
    if (rng.uniform() < options.view_fraction) {
      s.options.view = synth::kViews[1 + rng.next() % (synth::kViews.size() - 1)];  // [0] is palm
    }
  } else {
    s.pose = random_pose(rng, synth::HandShape::for_subject(*s.options.subject), options);
  }
  if (options.ball_fraction > 0.0 && rng.uniform() < options.ball_fraction) {
    const double radius = rng.uniform(kMinTrainingHeldRadiusMm, kMaxTrainingHeldRadiusMm);
    const bool bottle = options.bottle_share > 0.0 &&
                        synth::Rng::stream(seed, index, kBottleStream).uniform() < options.bottle_share;
    (bottle ? s.options.bottle_radius_mm : s.options.ball_radius_mm) = radius;
  }
  if (options.body_fraction > 0.0 && rng.uniform() < options.body_fraction &&
      s.options.view != synth::View::kHeadMounted) {
    s.body = true;
    s.options.background = synth::Background::kNearBody;
  }
  if (options.varied_fraction > 0.0 &&
      synth::Rng::stream(seed, index, kProportionStream).uniform() < options.varied_fraction) {
    s.options.proportions = synth::Proportions::kVaried;
  }
  if (options.armless_fraction > 0.0 &&
      synth::Rng::stream(seed, index, kArmStream).uniform() < options.armless_fraction) {
    s.options.arm = synth::Arm::kNone;
  }
  if (s.from_motion && options.rolled_fraction > 0.0) {
    synth::Rng rng_roll = synth::Rng::stream(seed, index, kRollStream);
    if (rng_roll.uniform() < options.rolled_fraction) s.options.roll_deg = rng_roll.uniform(-180.0, 180.0);
  }
  if (s.from_motion && options.distance_spread_mm > 0.0) {
    s.options.depth_offset_mm = synth::Rng::stream(seed, index, kDistanceStream)
                                    .uniform(options.distance_farther_only ? 0.0 : -options.distance_spread_mm,
                                             options.distance_spread_mm);
  }
  return s;
}

void render_scene(const Scene& scene, DepthInputBuilder& builder, RenderedScene& out) {
  const auto render = [&](const synth::SynthOptions& options, synth::SynthFrame& frame) {
    synth::SyntheticCamera cam(options);
    if (scene.from_motion) {
      cam.render(scene.frame, frame);
    } else {
      cam.render_pose(scene.pose, scene.frame, frame);
    }
  };
  render(scene.options, out.frame);
  if (scene.body) {
    // The hand and its forearm are where the same scene without a background has depth: gone, the
    // rest is what a free slot would be given.
    synth::SynthOptions alone = scene.options;
    alone.background = synth::Background::kNone;
    synth::SynthFrame hand;
    render(alone, hand);
    for (size_t i = 0; i < hand.depth.depth_mm.size(); ++i) {
      if (hand.depth.depth_mm[i] > 0.0F) out.frame.depth.depth_mm[i] = 0.0F;
    }
  }
  out.input = builder.build(out.frame.depth, std::nullopt);
}

LabelledImage crop_hand(const DepthInput& input, const std::vector<uint8_t>& truth) {
  const int w = input.camera.width;
  const int h = input.camera.height;
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!input.hand_mask[static_cast<size_t>(y) * w + x]) continue;
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
  }
  LabelledImage img;
  if (x1 < 0) return img;
  img.width = x1 - x0 + 1;
  img.height = y1 - y0 + 1;
  img.depth_mm.assign(static_cast<size_t>(img.width) * img.height, kBackgroundDepthMm);
  img.labels.assign(img.depth_mm.size(), LabelledImage::kOffMask);
  img.turn = hand_turn(input.unhinted_axis);  // built without a hint: finger_axis
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (!input.hand_mask[i] || input.filtered_mm[i] <= 0.0F) continue;
      const size_t j = static_cast<size_t>(y - y0) * img.width + (x - x0);
      img.depth_mm[j] = input.filtered_mm[i];
      img.labels[j] = std::min<uint8_t>(truth[i], static_cast<uint8_t>(kNumPartLabels));
      ++img.hand_pixels;
    }
  }
  return img;
}

std::vector<LabelledImage> make_dataset(uint64_t seed, int count, const SceneOptions& options, int threads,
                                        int min_hand_pixels, const std::function<void(int)>& progress) {
  std::vector<LabelledImage> images(static_cast<size_t>(std::max(0, count)));
  std::atomic<int> next{0};
  std::atomic<int> done{0};
  const auto work = [&]() {
    DepthInputConfig volume;
    volume.far_mm = options.volume_far_mm;
    DepthInputBuilder builder(volume);
    RenderedScene r;
    for (int i = next++; i < count; i = next++) {
      // Image i is the first of scenes i, i + count, i + 2 count, ... whose hand is big enough.
      for (int attempt = 0; attempt < kMaxSceneAttempts; ++attempt) {
        const auto index = static_cast<uint64_t>(i) + static_cast<uint64_t>(attempt) * static_cast<uint64_t>(count);
        render_scene(make_scene(seed, index, options), builder, r);
        LabelledImage img = crop_hand(r.input, r.frame.labels.pixels);
        if (img.hand_pixels >= min_hand_pixels || attempt + 1 == kMaxSceneAttempts) {
          images[static_cast<size_t>(i)] = std::move(img);
          break;
        }
      }
      ++done;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < std::max(1, threads); ++t) pool.emplace_back(work);
  if (progress) {
    std::thread own(work);
    while (done.load() < count) {
      progress(done.load());
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
    own.join();
    progress(count);
  } else {
    work();
  }
  for (auto& t : pool) t.join();
  return images;
}

void Confusion::add(const Confusion& other) {
  for (size_t t = 0; t < counts.size(); ++t) {
    for (size_t p = 0; p < counts.size(); ++p) counts[t][p] += other.counts[t][p];
  }
}

uint64_t Confusion::total() const {
  uint64_t n = 0;
  for (const auto& row : counts) {
    for (const auto c : row) n += c;
  }
  return n;
}

double Confusion::accuracy() const {
  uint64_t right = 0;
  for (size_t c = 0; c < counts.size(); ++c) right += counts[c][c];
  const uint64_t n = total();
  return n > 0 ? static_cast<double>(right) / static_cast<double>(n) : 0.0;
}

double Confusion::part_accuracy() const {
  uint64_t right = 0;
  uint64_t n = 0;
  for (size_t c = 1; c < counts.size(); ++c) {
    right += counts[c][c];
    for (const auto k : counts[c]) n += k;
  }
  return n > 0 ? static_cast<double>(right) / static_cast<double>(n) : 0.0;
}

double Confusion::class_recall(int c) const {
  const auto& row = counts[static_cast<size_t>(c)];
  uint64_t n = 0;
  for (const auto k : row) n += k;
  return n > 0 ? static_cast<double>(row[static_cast<size_t>(c)]) / static_cast<double>(n) : std::nan("");
}

std::string Confusion::table() const {
  static constexpr std::array<const char*, kPartForestClasses> kNames = {
      "bg", "palm", "th1", "th2", "th3", "ix1", "ix2", "mi1", "mi2", "ri1", "ri2", "li1", "li2"};
  std::string out = "truth\\pred ";
  char buf[64];
  for (const char* n : kNames) {
    std::snprintf(buf, sizeof buf, "%5s", n);
    out += buf;
  }
  out += "  pixels\n";
  for (size_t t = 0; t < counts.size(); ++t) {
    uint64_t n = 0;
    for (const auto k : counts[t]) n += k;
    std::snprintf(buf, sizeof buf, "%-10s ", kNames[t]);
    out += buf;
    for (size_t p = 0; p < counts.size(); ++p) {
      const double pct = n > 0 ? 100.0 * static_cast<double>(counts[t][p]) / static_cast<double>(n) : 0.0;
      std::snprintf(buf, sizeof buf, "%5.1f", pct);
      out += buf;
    }
    std::snprintf(buf, sizeof buf, "  %llu\n", static_cast<unsigned long long>(n));
    out += buf;
  }
  return out;
}

Confusion score_frame(const PartForest& forest, const DepthInput& input, const std::vector<uint8_t>& truth,
                      std::vector<uint8_t>& scratch) {
  Confusion c;
  forest.label(input, scratch);
  for (size_t i = 0; i < input.hand_mask.size(); ++i) {
    if (!input.hand_mask[i] || input.filtered_mm[i] <= 0.0F) continue;
    const size_t t = std::min<size_t>(truth[i], kNumPartLabels);
    const size_t p = std::min<size_t>(scratch[i], kNumPartLabels);
    ++c.counts[t][p];
  }
  return c;
}

HeldOutResult evaluate_motions(const PartForest& forest, uint64_t seed_base, int frames_per_motion,
                               synth::View view, synth::Proportions proportions) {
  HeldOutResult result;
  DepthInputBuilder builder;
  synth::SynthFrame frame;
  std::vector<uint8_t> scratch;
  for (size_t m = 0; m < synth::kMotionNames.size(); ++m) {
    synth::SynthOptions o;
    o.motion = std::string(synth::kMotionNames[m]);
    o.frames = kHeldOutSequenceFrames;
    o.seed = seed_base + m;
    o.background = kBackgrounds[m % kBackgrounds.size()];
    o.view = view;
    o.proportions = proportions;
    synth::SyntheticCamera cam(o);
    for (int k = 0; k < frames_per_motion; ++k) {
      const int i = static_cast<int>((static_cast<int64_t>(k) * kHeldOutSequenceFrames + kHeldOutSequenceFrames / 2) /
                                     std::max(1, frames_per_motion));
      cam.render(i, frame);
      const DepthInput& input = builder.build(frame.depth, std::nullopt);
      if (!input.has_hand()) continue;
      result.per_motion[m].add(score_frame(forest, input, frame.labels.pixels, scratch));
      ++result.frames;
    }
    result.overall.add(result.per_motion[m]);
  }
  return result;
}

Confusion evaluate_scenes(const PartForest& forest, uint64_t seed, int count, const SceneOptions& options) {
  Confusion c;
  DepthInputBuilder builder;
  RenderedScene r;
  std::vector<uint8_t> scratch;
  for (int i = 0; i < count; ++i) {
    render_scene(make_scene(seed, static_cast<uint64_t>(i), options), builder, r);
    if (!r.input.has_hand()) continue;
    c.add(score_frame(forest, r.input, r.frame.labels.pixels, scratch));
  }
  return c;
}

}  // namespace handtrack::forest
