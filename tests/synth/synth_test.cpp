// handtrack::synth: the synthetic camera's ground truth must agree with its pixels, its kinematics
// and its noise model, and be reproducible.

#include "handtrack/synth/synthetic_camera.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <ctime>
#include <limits>
#include <numbers>
#include <numeric>
#include <vector>

namespace {

using handtrack::Joints;
using handtrack::kNumFingers;
using namespace handtrack::synth;

SynthOptions clean_options(const std::string& motion, Background bg = Background::kBody, int w = 320, int h = 240) {
  SynthOptions o;
  o.motion = motion;
  o.frames = 300;
  o.seed = 7;
  o.noise = false;
  o.background = bg;
  o.camera = default_camera(w, h);
  return o;
}

// The palm pixels of `plain` that `held` (the same frame with a held object) shows as the object
// (label 0), nearer the camera than the palm was.
size_t palm_pixels_hidden_by_object(const SynthFrame& plain, const SynthFrame& held) {
  size_t hidden = 0;
  for (size_t i = 0; i < plain.depth.depth_mm.size(); ++i) {
    const bool over_palm = plain.labels.pixels[i] == handtrack::kPalm && held.labels.pixels[i] == 0;
    hidden += over_palm && held.depth.depth_mm[i] < plain.depth.depth_mm[i] ? 1 : 0;
  }
  return hidden;
}

int pixel_index(const handtrack::CameraIntrinsics& cam, const Eigen::Vector2d& uv) {
  const int u = static_cast<int>(std::lround(uv.x()));
  const int v = static_cast<int>(std::lround(uv.y()));
  if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) return -1;
  return v * cam.width + u;
}

// With the fingers extended toward the image top and the palm toward the camera (adbadd and the
// open hand of flexex1), every fingertip is in view: its pixel carries the finger's distal label
// and sees the front of the tip sphere, tip_z - tip radius.
void expect_fingertips_on_distal_pixels(const std::string& motion, const std::vector<int>& frames, int w, int h) {
  SyntheticCamera cam(clean_options(motion, Background::kBody, w, h));
  for (int i : frames) {
    const SynthFrame f = cam.render(i);
    for (int finger = 0; finger < kNumFingers; ++finger) {
      SCOPED_TRACE(motion + " frame " + std::to_string(i) + " finger " + std::to_string(finger));
      const Eigen::Vector3d tip = *f.fingertips[static_cast<size_t>(finger)];
      const int index = pixel_index(cam.camera(), cam.camera().project(tip));
      ASSERT_GE(index, 0) << "fingertip outside the image";
      EXPECT_EQ(f.labels.pixels[static_cast<size_t>(index)], handtrack::part_label(finger, 2));
      const double radius = cam.shape().fingers[static_cast<size_t>(finger)].radius_mm[3];
      EXPECT_NEAR(f.depth.depth_mm[static_cast<size_t>(index)], tip.z() - radius, 1.5);
    }
  }
}

TEST(SynthCamera, FingertipsProjectOntoTheirDistalLabelAtTheSkinDepth) {
  expect_fingertips_on_distal_pixels("adbadd", {0, 37, 75, 150, 190, 240, 299}, 320, 240);
  expect_fingertips_on_distal_pixels("flexex1", {0}, 320, 240);
}

TEST(SynthCamera, Renders640x480WithScaledIntrinsics) {
  SyntheticCamera cam(clean_options("adbadd", Background::kBody, 640, 480));
  EXPECT_NEAR(cam.camera().fx, 2 * 224.502, 1e-9);
  EXPECT_NEAR(cam.camera().fy, 2 * 230.494, 1e-9);
  EXPECT_DOUBLE_EQ(cam.camera().cx, 320.0);
  const SynthFrame f = cam.render(10);
  ASSERT_EQ(f.depth.width(), 640);
  ASSERT_EQ(f.depth.depth_mm.size(), 640u * 480u);
  ASSERT_EQ(f.labels.pixels.size(), 640u * 480u);
  // The same scene as at 320x240: four times the hand pixels, same fingertip depths.
  SyntheticCamera small(clean_options("adbadd", Background::kBody, 320, 240));
  const SynthFrame g = small.render(10);
  const auto hand_pixels = [](const SynthFrame& x) {
    return std::count_if(x.labels.pixels.begin(), x.labels.pixels.end(), [](uint8_t l) { return l != 0; });
  };
  EXPECT_NEAR(static_cast<double>(hand_pixels(f)) / static_cast<double>(hand_pixels(g)), 4.0, 0.3);
  expect_fingertips_on_distal_pixels("adbadd", {10, 200}, 640, 480);
}

TEST(SynthCamera, BoneLengthsArePreservedAndFollowTheSubjectScale) {
  const HandShape mean = HandShape::mean_adult();
  for (auto name : kMotionNames) {
    SynthOptions o = clean_options(std::string(name));
    o.subject = SubjectScale{1.07, 0.93};
    SyntheticCamera cam(o);
    for (int i = 0; i < 300; i += 13) {
      const Joints j = cam.render(i).joints;
      for (int f = 0; f < kNumFingers; ++f) {
        for (int bone = 0; bone < 3; ++bone) {
          const double length = (j[static_cast<size_t>(handtrack::joint_index(f, bone + 1))] -
                                 j[static_cast<size_t>(handtrack::joint_index(f, bone))])
                                    .norm();
          EXPECT_NEAR(length, 1.07 * mean.fingers[static_cast<size_t>(f)].bone_length_mm[static_cast<size_t>(bone)],
                      1e-6)
              << name << " frame " << i;
        }
        // The base joints are rigid in the hand frame: their distance to the wrist is fixed.
        const Eigen::Vector3d b = mean.fingers[static_cast<size_t>(f)].base_mm;
        const Eigen::Vector3d scaled(0.93 * b.x(), 1.07 * b.y(), b.z());
        EXPECT_NEAR((j[static_cast<size_t>(handtrack::joint_index(f, 0))] - j[0]).norm(), scaled.norm(), 1e-6);
      }
    }
  }
}

TEST(SynthCamera, RandomSubjectsStayWithinTenPercentAndDependOnTheSeed) {
  std::vector<double> lengths;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    SynthOptions o = clean_options("flexex1");
    o.seed = seed;
    SyntheticCamera cam(o);
    EXPECT_GE(cam.subject().length, 0.9);
    EXPECT_LE(cam.subject().length, 1.1);
    EXPECT_GE(cam.subject().width, 0.9);
    EXPECT_LE(cam.subject().width, 1.1);
    lengths.push_back(cam.subject().length);
  }
  std::sort(lengths.begin(), lengths.end());
  EXPECT_GT(lengths.back() - lengths.front(), 0.05) << "subjects hardly vary with the seed";
}

// Proportions::kVaried: each hand's fingers get their own lengths and the fingers and palm their
// own thickness, drawn from the seed within the documented spreads; the size and the motion's
// timing stay the seed's, and the motions still do what they say with the new fingers (the pinch
// closes on its tips).
TEST(SynthCamera, VariedProportionsGiveEachFingerItsOwnLengthAndKeepTheSize) {
  const HandShape mean = HandShape::mean_adult();
  std::vector<double> index_lengths;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    SynthOptions o = clean_options("pinch");
    o.seed = seed;
    const SyntheticCamera as_mean(o);
    o.proportions = Proportions::kVaried;
    const SyntheticCamera varied(o);
    const SubjectScale& s = varied.subject();
    EXPECT_EQ(s.length, as_mean.subject().length) << "seed " << seed;
    EXPECT_EQ(s.width, as_mean.subject().width);
    for (size_t f = 0; f < kNumFingers; ++f) {
      EXPECT_GE(s.finger_length[f], 0.94);
      EXPECT_LE(s.finger_length[f], 1.06);
      EXPECT_NEAR(varied.shape().fingers[f].bone_length_mm[0],
                  mean.fingers[f].bone_length_mm[0] * s.length * s.finger_length[f], 1e-9);
      EXPECT_NEAR(varied.shape().fingers[f].radius_mm[0], mean.fingers[f].radius_mm[0] * s.width * s.finger_girth,
                  1e-9);
    }
    index_lengths.push_back(s.finger_length[handtrack::kIndex]);
    for (double t : {s.finger_girth, s.palm_thickness}) {
      EXPECT_GE(t, 0.85);
      EXPECT_LE(t, 1.15);
    }
    double closest = 1e9;
    for (int i = 0; i < 300; i += 2) {
      const Joints j = camera_frame_joints(varied.shape(), varied.pose(i));
      closest = std::min(closest, (j[static_cast<size_t>(handtrack::fingertip_joint(handtrack::kThumb))] -
                                   j[static_cast<size_t>(handtrack::fingertip_joint(handtrack::kIndex))])
                                      .norm());
    }
    const double contact = varied.shape().fingers[handtrack::kThumb].radius_mm[3] +
                           varied.shape().fingers[handtrack::kIndex].radius_mm[3];
    EXPECT_NEAR(closest, contact, 2.0) << "seed " << seed << ": the pinch misses with these fingers";
  }
  std::sort(index_lengths.begin(), index_lengths.end());
  EXPECT_GT(index_lengths.back() - index_lengths.front(), 0.06) << "the index's length hardly varies with the seed";
}

// --palm-arch: the index and little fingers' knuckles move toward the palm's side by the arch at
// their x, the middle finger's hardly; in the palm view the camera sees the palm's sides nearer
// and its middle where it was, and the truth (joints) carries the arched knuckles.
TEST(SynthCamera, AnArchedPalmBringsItsSidesTowardThePalmAndKeepsItsMiddle) {
  constexpr double kArchMm = 10.0;
  SynthOptions o = clean_options("adbadd");
  SyntheticCamera flat(o);
  o.palm_arch_mm = kArchMm;
  SyntheticCamera arched(o);
  const double w = flat.subject().width;
  EXPECT_EQ(arched.subject().palm_arch_mm, kArchMm);
  const auto base_shift = [&](int finger) {
    const auto f = static_cast<size_t>(finger);
    return arched.shape().fingers[f].base_mm - flat.shape().fingers[f].base_mm;
  };
  // The arch at hand-frame x, worked out here rather than by palm_arch_offset_mm, which it checks.
  const auto arch_at = [&](double x) {
    const double u = x / (27.0 * w);
    return kArchMm * u * u;
  };
  const auto expected = [&](int finger) { return arch_at(flat.shape().fingers[static_cast<size_t>(finger)].base_mm.x()); };
  for (int finger : {handtrack::kIndex, handtrack::kMiddle, handtrack::kLittle}) {
    SCOPED_TRACE("finger " + std::to_string(finger));
    EXPECT_NEAR(base_shift(finger).z(), expected(finger), 1e-9);
    EXPECT_NEAR(base_shift(finger).head<2>().norm(), 0.0, 1e-12);
  }
  EXPECT_GT(base_shift(handtrack::kLittle).z(), 11.0);
  EXPECT_LT(base_shift(handtrack::kMiddle).z(), 0.5);

  // Frame 0: the open hand, palm toward the camera. The depth at the index and little knuckles'
  // pixels comes nearer by about their shift (the palm's surface there moved with them); at the
  // palm's middle it stays within a millimetre.
  const SynthFrame f_flat = flat.render(0);
  const SynthFrame f_arched = arched.render(0);
  const auto depth_at = [&](const SynthFrame& f, const Eigen::Vector3d& p) {
    const int i = pixel_index(flat.camera(), flat.camera().project(p));
    EXPECT_GE(i, 0);
    return i < 0 ? 0.0 : static_cast<double>(f.depth.depth_mm[static_cast<size_t>(i)]);
  };
  for (int finger : {handtrack::kIndex, handtrack::kLittle}) {
    const Eigen::Vector3d knuckle = f_flat.joints[static_cast<size_t>(handtrack::joint_index(finger, 0))];
    const double nearer = depth_at(f_flat, knuckle) - depth_at(f_arched, knuckle);
    EXPECT_GT(nearer, 0.5 * expected(finger)) << "finger " << finger;
    EXPECT_LT(nearer, 1.5 * expected(finger)) << "finger " << finger;
    EXPECT_GT((f_arched.joints[static_cast<size_t>(handtrack::joint_index(finger, 0))] - knuckle).norm(),
              0.99 * expected(finger));
  }
  const Eigen::Vector3d middle = (f_flat.joints[0] + f_flat.joints[static_cast<size_t>(
                                                        handtrack::joint_index(handtrack::kMiddle, 0))]) /
                                 2.0;
  EXPECT_NEAR(depth_at(f_arched, middle), depth_at(f_flat, middle), 1.0);

  // --palm-arch-shape back: the front stays flat (the palm view's depth at the knuckles within 1 mm,
  // the fingers' bases where they were) and the back recedes at its sides: seen from behind, the
  // palm's little-finger side, three quarters of the way from the wrist to that knuckle, is about
  // the arch at its x farther.
  o.palm_arch = PalmArch::kBack;
  SyntheticCamera back_only(o);
  EXPECT_EQ(back_only.shape().fingers[handtrack::kLittle].base_mm, flat.shape().fingers[handtrack::kLittle].base_mm);
  const SynthFrame f_back_only = back_only.render(0);
  for (int finger : {handtrack::kIndex, handtrack::kLittle}) {
    const Eigen::Vector3d knuckle = f_flat.joints[static_cast<size_t>(handtrack::joint_index(finger, 0))];
    EXPECT_NEAR(depth_at(f_back_only, knuckle), depth_at(f_flat, knuckle), 1.0) << "finger " << finger;
  }
  o.view = View::kBack;
  o.palm_arch_mm = 0.0;
  SyntheticCamera flat_back(o);
  o.palm_arch_mm = kArchMm;
  SyntheticCamera arched_back(o);
  const SynthFrame b_flat = flat_back.render(0);
  const SynthFrame b_arched = arched_back.render(0);
  const auto little_mcp = static_cast<size_t>(handtrack::joint_index(handtrack::kLittle, 0));
  const Eigen::Vector3d side = 0.25 * b_flat.joints[0] + 0.75 * b_flat.joints[little_mcp];
  const Joints in_hand = hand_frame_joints(flat_back.shape(), flat_back.pose(0));
  const double side_x = 0.25 * in_hand[0].x() + 0.75 * in_hand[little_mcp].x();
  const double side_arch = arch_at(side_x);
  const double farther = depth_at(b_arched, side) - depth_at(b_flat, side);
  EXPECT_GT(side_arch, 4.0);
  EXPECT_GT(farther, 0.5 * side_arch);
  EXPECT_LT(farther, 1.5 * side_arch);
}

TEST(SynthCamera, SameSeedSameFramesDifferentSeedDifferentNoise) {
  SynthOptions o = clean_options("random");
  o.noise = true;
  SyntheticCamera a(o), b(o);
  o.seed = 8;
  o.subject = a.subject();  // same hand, different noise
  SyntheticCamera c(o);
  for (int i : {0, 123, 299, 450}) {
    const SynthFrame fa = a.render(i), fb = b.render(i), fc = c.render(i);
    EXPECT_EQ(fa.depth.depth_mm, fb.depth.depth_mm) << "frame " << i;
    EXPECT_EQ(fa.labels.pixels, fb.labels.pixels);
    EXPECT_NE(fa.depth.depth_mm, fc.depth.depth_mm);
    for (size_t j = 0; j < fa.joints.size(); ++j) EXPECT_EQ(fa.joints[j], fc.joints[j]);
  }
  // Random access: frame 123 rendered after others equals a fresh render.
  SyntheticCamera d(o);
  EXPECT_EQ(d.render(123).depth.depth_mm, c.render(123).depth.depth_mm);
}

TEST(SynthNoise, DepthNoiseFollowsTheModelAndEdgesFlyAndDropouts) {
  SynthOptions o = clean_options("flexex1", Background::kBody);
  SyntheticCamera clean(o);
  o.noise = true;
  SyntheticCamera noisy(o);
  const NoiseParams np;
  double sum = 0, sum2 = 0;
  size_t count = 0, interior = 0, dropped = 0, flying = 0;
  for (int i = 0; i < 300; i += 20) {
    const SynthFrame c = clean.render(i), n = noisy.render(i);
    const int w = c.depth.width();
    for (int v = 1; v + 1 < c.depth.height(); ++v) {
      for (int u = 1; u + 1 < w; ++u) {
        const float z = c.depth.at(u, v);
        if (z <= 0) continue;
        float max_jump = 0;
        for (auto [du, dv] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
          const float zn = c.depth.at(u + du, v + dv);
          max_jump = std::max(max_jump, zn > 0 ? std::abs(zn - z) : 1e9f);
        }
        const float zn = n.depth.at(u, v);
        if (max_jump > 50 && zn > 0 && std::abs(zn - z) > std::max(10.0, 5.0 * np.sigma_mm(z)) &&
            std::abs(zn - z) < max_jump) {
          ++flying;
        }
        if (max_jump > 3) continue;  // interior pixels only below
        ++interior;
        if (zn == 0) {
          ++dropped;
          continue;
        }
        if (z >= 385 && z <= 415) {  // "at a known depth": 400 +- 15 mm
          const double r = zn - z;
          sum += r;
          sum2 += r * r;
          ++count;
        }
      }
    }
  }
  ASSERT_GT(count, 2000u);
  const double mean = sum / static_cast<double>(count);
  const double sd = std::sqrt(sum2 / static_cast<double>(count) - mean * mean);
  // Model: sigma(400 mm) = k 400^2 = 1.5 mm, plus 1 mm quantisation (variance 1/12 mm^2).
  const double expected = std::sqrt(np.sigma_mm(400) * np.sigma_mm(400) + 1.0 / 12.0);
  EXPECT_NEAR(np.sigma_mm(400), 1.5, 1e-9);
  std::printf("noise at 400 mm: sd %.3f mm (model %.3f), mean %.3f, %zu px; drop rate %.4f; %zu flying\n", sd,
              expected, mean, count, static_cast<double>(dropped) / static_cast<double>(interior), flying);
  EXPECT_NEAR(sd, expected, 0.1 * expected);
  EXPECT_NEAR(mean, 0.0, 0.1);
  // Interior dropouts: the random rate plus a few grazing ones on curved skin.
  const double drop_rate = static_cast<double>(dropped) / static_cast<double>(interior);
  EXPECT_GT(drop_rate, 0.5 * np.dropout_probability);
  EXPECT_LT(drop_rate, 0.05);
  EXPECT_GT(flying, 100u) << "no flying pixels at depth edges";

  // The same count without flying pixels is near zero: the count above measures the effect.
  o.noise_params.flying_pixel_probability = 0.0;
  SyntheticCamera steady(o);
  size_t off_edge = 0;
  for (int i = 0; i < 300; i += 20) {
    const SynthFrame c = clean.render(i), n = steady.render(i);
    for (size_t k = 0; k < c.depth.depth_mm.size(); ++k) {
      const float z = c.depth.depth_mm[k], zn = n.depth.depth_mm[k];
      off_edge += (z > 0 && zn > 0 && std::abs(zn - z) > std::max(10.0, 5.0 * np.sigma_mm(z))) ? 1 : 0;
    }
  }
  EXPECT_LT(off_edge, 10u);
}

TEST(SynthNoise, QuantisedAndWithinRange) {
  SynthOptions o = clean_options("pinch", Background::kTable);
  o.noise = true;
  SyntheticCamera cam(o);
  const SynthFrame f = cam.render(42);
  size_t valid = 0;
  for (size_t i = 0; i < f.depth.depth_mm.size(); ++i) {
    const float z = f.depth.depth_mm[i];
    if (z == 0) {
      EXPECT_EQ(f.labels.pixels[i], 0) << "a label on a pixel without depth";
      continue;
    }
    ++valid;
    EXPECT_EQ(z, std::round(z));
    EXPECT_GE(z, 100.0f);
    EXPECT_LE(z, 1500.0f);
  }
  EXPECT_GT(valid, 10000u);  // the table fills the lower part of the image
}

// noise.hpp item 6 on a scene whose shadow is known: a wall at 600 mm and, in front of it at 400
// mm, a wide block (columns 100-139) and a narrow one (200-203). fx 225 and a projector 50 mm to
// the camera's left shift a column by fx 50 / z: 28.1 px at the blocks, 18.75 at the wall. The
// wall's pixel u is in shadow where round(u + 18.75) = u + 19 falls among the blocks' projector
// columns, u + 28 for u in [a, b]: 140-148 (fx 50 (1/400 - 1/600) = 9.4 px) beside the wide block,
// 209-212 beside the narrow one, which leaves 204-208 lit between the narrow block and its shadow.
TEST(SynthNoise, AProjectorsShadowFallsOnTheFarSurfaceAwayFromTheProjector) {
  constexpr int w = 320, h = 2;
  std::vector<float> depth(w * h, 600.0f);
  for (int v = 0; v < h; ++v) {
    for (int u = 100; u < 140; ++u) depth[static_cast<size_t>(v * w + u)] = 400.0f;
    for (int u = 200; u < 204; ++u) depth[static_cast<size_t>(v * w + u)] = 400.0f;
  }
  depth[5] = depth[w + 5] = std::numeric_limits<float>::infinity();  // no surface: no depth, no shadow
  const auto shaded = [&](double projector_x) {
    const std::vector<uint8_t> lit = projector_lit(depth, w, h, 225.0, projector_x);
    std::vector<int> columns;
    for (int u = 0; u < w; ++u) {
      EXPECT_EQ(lit[static_cast<size_t>(u)], lit[static_cast<size_t>(w + u)]) << "rows differ at " << u;
      if (lit[static_cast<size_t>(u)] == 0) columns.push_back(u);
    }
    return columns;
  };
  std::vector<int> expected = {5};
  for (int u = 140; u < 149; ++u) expected.push_back(u);
  for (int u = 209; u < 213; ++u) expected.push_back(u);
  EXPECT_EQ(shaded(-50.0), expected);
  // The projector to the right: the bands to the image left, 91-99 and 191-194.
  expected = {5};
  for (int u = 91; u < 100; ++u) expected.push_back(u);
  for (int u = 191; u < 195; ++u) expected.push_back(u);
  EXPECT_EQ(shaded(50.0), expected);
  EXPECT_EQ(shaded(0.0), std::vector<int>{5});
}

TEST(SynthNoise, CorrelatedNoiseHasUnitVarianceAndTheBlursCorrelation) {
  // Ten fields: a blur of 2.5 px leaves about 1,000 independent values in one 320 x 240 field, too
  // few for the mean and variance to 0.05.
  Rng rng(3);
  constexpr int w = 320, h = 240, fields = 10;
  constexpr double sigma = 2.5;
  const std::array<int, 4> lags = {1, 3, 5, 10};
  double sum = 0.0, sum_sq = 0.0;
  std::array<double, 4> products{};
  for (int k = 0; k < fields; ++k) {
    const std::vector<float> f = rng.correlated_normals(w, h, sigma);
    ASSERT_EQ(f.size(), static_cast<size_t>(w * h));
    for (float x : f) sum += x, sum_sq += static_cast<double>(x) * x;
    for (size_t l = 0; l < lags.size(); ++l) {
      double c = 0.0;
      for (int v = 0; v < h; ++v) {
        for (int u = 0; u + lags[l] < w; ++u) c += f[static_cast<size_t>(v * w + u)] * f[static_cast<size_t>(v * w + u + lags[l])];
      }
      products[l] += c / static_cast<double>(h * (w - lags[l]));
    }
  }
  const double n = static_cast<double>(fields) * w * h;
  const double mean = sum / n;
  const double var = sum_sq / n - mean * mean;
  EXPECT_NEAR(mean, 0.0, 0.03);
  EXPECT_NEAR(var, 1.0, 0.05);
  // A Gaussian blur of s px leaves white noise correlated exp(-L^2 / (4 s^2)) at L px.
  for (size_t l = 0; l < lags.size(); ++l) {
    EXPECT_NEAR(products[l] / fields / var, std::exp(-lags[l] * lags[l] / (4.0 * sigma * sigma)), 0.03) << "lag " << lags[l];
  }
}

// A structured-light camera is the same camera for either hand: the projector's shadow lies to
// the image right of the hand whether it is a right or a left one (left hands are rendered as the
// right hand's mirror image, noise.hpp item 6 on the other side).
TEST(SynthNoise, AStructuredLightCamerasShadowLiesOnItsOwnSideForEitherHand) {
  for (Handedness hand : {Handedness::kRight, Handedness::kLeft}) {
    SCOPED_TRACE(std::string(handedness_name(hand)));
    SynthOptions o = clean_options("adbadd", Background::kBody);
    o.hand = hand;
    o.noise = true;
    SyntheticCamera generic(o);
    o.noise_params = sensor_noise(Sensor::kStructuredLight, o.camera.width);
    SyntheticCamera structured(o);
    const SynthFrame g = generic.render(100), s = structured.render(100);
    // Body pixels (label 0, depth) the structured light loses, by their side of the hand's pixels
    // on the same row: a band of zeros beside the hand's outline.
    int right_of_hand = 0, left_of_hand = 0;
    const int w = g.depth.width();
    for (int v = 0; v < g.depth.height(); ++v) {
      int first = w, last = -1;
      for (int u = 0; u < w; ++u) {
        if (g.labels.pixels[static_cast<size_t>(v * w + u)] != 0) first = std::min(first, u), last = std::max(last, u);
      }
      if (last < 0) continue;
      for (int u = 0; u < w; ++u) {
        const auto i = static_cast<size_t>(v * w + u);
        if (g.labels.pixels[i] != 0 || g.depth.depth_mm[i] == 0 || s.depth.depth_mm[i] != 0) continue;
        right_of_hand += u > last && u <= last + 15 ? 1 : 0;
        left_of_hand += u < first && u >= first - 15 ? 1 : 0;
      }
    }
    EXPECT_GT(right_of_hand, 200);
    EXPECT_LT(left_of_hand, right_of_hand / 10);
  }
}

TEST(SynthScenes, ADeskUnderTheHandAndABallInIt) {
  // The desk (Background::kDesk) fills the image behind the hand and touches it: some hand pixel
  // has a desk pixel beside it less than 10 mm deeper. A held ball covers the palm (label 0, in
  // front of where the palm was).
  SynthOptions o = clean_options("pinch", Background::kDesk);
  SyntheticCamera desk(o);
  const SynthFrame d = desk.render(60);
  const int w = d.depth.camera.width;
  size_t desk_pixels = 0;
  bool touching = false;
  for (size_t i = 1; i < d.depth.depth_mm.size(); ++i) {
    desk_pixels += d.labels.pixels[i] == 0 && d.depth.depth_mm[i] > 0 ? 1 : 0;
    const bool edge = (d.labels.pixels[i] == 0) != (d.labels.pixels[i - 1] == 0) && i % w != 0;
    touching = touching || (edge && d.depth.depth_mm[i] > 0 && d.depth.depth_mm[i - 1] > 0 &&
                            std::abs(d.depth.depth_mm[i] - d.depth.depth_mm[i - 1]) < 10.0F);
  }
  EXPECT_GT(desk_pixels, d.depth.depth_mm.size() / 2);
  EXPECT_TRUE(touching);

  SynthOptions plain = clean_options("pinch");
  SynthOptions ball = plain;
  ball.ball_radius_mm = 35.0;
  const SynthFrame a = SyntheticCamera(plain).render(60);
  const SynthFrame b = SyntheticCamera(ball).render(60);
  EXPECT_GT(palm_pixels_hidden_by_object(a, b), 500u);
  ball.ball_radius_mm = 150.0;
  EXPECT_THROW(SyntheticCamera{ball}, std::invalid_argument);
  o.motion = "two_apart";
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);  // the desk is for one-hand motions
}

TEST(SynthScenes, ABottleHeldAcrossThePalmReachesPastBothSidesOfTheHand) {
  // A bottle (SynthOptions::bottle_radius_mm) lies across the palm: it covers palm pixels (label 0,
  // nearer than the palm was), and along the image row through the palm centre it shows on both
  // sides of the hand, where the frame without it has no hand.
  SynthOptions plain = clean_options("pinch");
  SynthOptions bottle = plain;
  bottle.bottle_radius_mm = 30.0;
  const SynthFrame a = SyntheticCamera(plain).render(60);
  const SynthFrame b = SyntheticCamera(bottle).render(60);
  const int w = a.depth.camera.width;
  EXPECT_GT(palm_pixels_hidden_by_object(a, b), 500u);
  // The row of the palm pixels' centroid: the hand's extent in it, and the bottle's nearer pixels.
  double v_sum = 0.0;
  size_t palm = 0;
  for (size_t i = 0; i < a.labels.pixels.size(); ++i) {
    if (a.labels.pixels[i] != handtrack::kPalm) continue;
    v_sum += static_cast<double>(i / w);
    ++palm;
  }
  ASSERT_GT(palm, 0u);
  const auto row = static_cast<size_t>(v_sum / static_cast<double>(palm));
  int hand_lo = w, hand_hi = -1, bottle_lo = w, bottle_hi = -1;
  for (int u = 0; u < w; ++u) {
    const size_t i = row * w + static_cast<size_t>(u);
    if (a.labels.pixels[i] != 0) hand_lo = std::min(hand_lo, u), hand_hi = std::max(hand_hi, u);
    const bool nearer = b.depth.depth_mm[i] > 0 && (a.depth.depth_mm[i] == 0 || b.depth.depth_mm[i] < a.depth.depth_mm[i] - 20);
    if (b.labels.pixels[i] == 0 && nearer) bottle_lo = std::min(bottle_lo, u), bottle_hi = std::max(bottle_hi, u);
  }
  EXPECT_LT(bottle_lo, hand_lo);
  EXPECT_GT(bottle_hi, hand_hi);
  SynthOptions both = bottle;
  both.ball_radius_mm = 30.0;
  EXPECT_THROW(SyntheticCamera{both}, std::invalid_argument);  // one held object at a time
  bottle.bottle_radius_mm = 150.0;
  EXPECT_THROW(SyntheticCamera{bottle}, std::invalid_argument);
}

TEST(SynthScenes, ANearBodyIsInsideTheWorkingVolumeBehindTheHand) {
  // Background::kNearBody: what is not the hand (label 0: the forearm, torso and head) covers more
  // of the tracker's 150-600 mm working volume than a hand and forearm can (400 cm^2); with the
  // body background only the forearm is there.
  const auto not_hand_in_volume_mm2 = [](Background bg) {
    const SynthFrame f = SyntheticCamera(clean_options("pinch", bg)).render(60);
    const auto& cam = f.depth.camera;
    double area = 0.0;
    for (size_t i = 0; i < f.depth.depth_mm.size(); ++i) {
      const float z = f.depth.depth_mm[i];
      if (f.labels.pixels[i] == 0 && z >= 150.0F && z <= 600.0F) area += static_cast<double>(z) * z / (cam.fx * cam.fy);
    }
    return area;
  };
  EXPECT_GT(not_hand_in_volume_mm2(Background::kNearBody), 40000.0);
  EXPECT_LT(not_hand_in_volume_mm2(Background::kBody), 10000.0);
  EXPECT_EQ(parse_background("near-body"), Background::kNearBody);
}

TEST(SynthScenes, ANearBodyStaysApartFromFingersThatCurlTowardIt) {
  // A user close to the camera holds the hand in front of the body. Where the fingers curl or tip
  // toward it (the back and side views, fingers tipped away) the user sits farther back than in
  // the palm view (views.hpp near_body_behind_mm): wherever the hand (not its forearm) is seen over
  // the head or the torso, the body is more than 30 mm behind it, more than the tracker's
  // continuity_mm (25), so that the two are apart in depth. As near as in the palm view, the
  // fingers went into the head: 45.6 mm deep (fingers tipped away, adbadd, subject 2), 19.7 (side
  // view), 15.6 (back view). (In the palm view the random motion brings the hand within 12 mm of
  // the head, as a hand may reach up to it: kept as it is.)
  for (const View view : {View::kBack, View::kSide, View::kFingersAway}) {
    for (const char* motion : {"adbadd", "fingercount", "fingerwave", "flexex1", "pinch", "random", "tigergrasp"}) {
      for (uint64_t seed = 1; seed <= 7; ++seed) {
        SCOPED_TRACE(std::string(view_name(view)) + " " + motion + " subject " + std::to_string(seed));
        SynthOptions body = clean_options(motion, Background::kNearBody);
        body.view = view;
        body.seed = seed;
        SynthOptions alone = body;
        alone.background = Background::kNone;
        SyntheticCamera with_body(body);
        SyntheticCamera hand_alone(alone);
        HandPose gone;  // the hand and its forearm behind the camera: the body alone
        gone.translation_mm = Eigen::Vector3d(0.0, 0.0, -5000.0);
        SynthFrame body_alone;
        with_body.render_pose(gone, 0, body_alone);
        double nearest_gap = std::numeric_limits<double>::infinity();
        for (int frame = 0; frame < 300; frame += 10) {
          const SynthFrame hand = hand_alone.render(frame);
          for (size_t i = 0; i < hand.labels.pixels.size(); ++i) {
            const float behind = body_alone.depth.depth_mm[i];
            if (hand.labels.pixels[i] == 0 || behind <= 0.0F) continue;
            nearest_gap = std::min(nearest_gap, static_cast<double>(behind - hand.depth.depth_mm[i]));
          }
        }
        EXPECT_GT(nearest_gap, 30.0);
      }
    }
  }
}

TEST(SynthMotions, StayWithinJointLimitsDepthAndImage) {
  const JointLimits limits = JointLimits::defaults();
  for (auto name : kMotionNames) {
    SyntheticCamera cam(clean_options(std::string(name)));
    size_t joints_inside = 0, joints_total = 0;
    for (int i = 0; i < 600; i += 3) {  // beyond 300 the motion plays back and forth
      const HandPose p = cam.pose(i);
      ASSERT_TRUE(limits.contains(p)) << name << " frame " << i;
      const Joints j = camera_frame_joints(cam.shape(), p);
      const Eigen::Matrix3d R = camera_R_hand(p.rotation);
      const Eigen::Vector3d palm = p.translation_mm + R * cam.shape().palm_centre_mm;
      EXPECT_GT(palm.z(), 300.0) << name;
      EXPECT_LT(palm.z(), 500.0) << name;
      const Eigen::Vector2d uv = cam.camera().project(palm);
      EXPECT_TRUE(uv.x() > 0 && uv.x() < 320 && uv.y() > 0 && uv.y() < 240) << name << " palm leaves the image";
      for (const auto& q : j) {
        EXPECT_GT(q.z(), 250.0) << name;
        const Eigen::Vector2d w = cam.camera().project(q);
        joints_inside += (w.x() >= 0 && w.x() < 320 && w.y() >= 0 && w.y() < 240) ? 1 : 0;
        ++joints_total;
      }
    }
    EXPECT_GT(static_cast<double>(joints_inside) / static_cast<double>(joints_total), 0.97) << name;
  }
}

// Mean joint speed over a span of frames (rad/frame over the 20 angles; random: global rotation).
double mean_speed(const SyntheticCamera& cam, bool global, int from, int to) {
  double total = 0;
  for (int i = from; i < to; ++i) {
    const HandPose a = cam.pose(i), b = cam.pose(i + 1);
    if (global) {
      const Eigen::Matrix3d d = camera_R_hand(b.rotation) * camera_R_hand(a.rotation).transpose();
      total += Eigen::AngleAxisd(d).angle();
    } else {
      total += (b.to_params().tail<20>() - a.to_params().tail<20>()).norm();
    }
  }
  return total / (to - from);
}

TEST(SynthMotions, SecondHalfIsTwoToThreeTimesFasterAndSmooth) {
  for (auto name : kMotionNames) {
    SyntheticCamera cam(clean_options(std::string(name)));
    const bool global = name == "random";
    const double slow = mean_speed(cam, global, 0, 140), fast = mean_speed(cam, global, 160, 299);
    EXPECT_GT(slow, 0.002) << name << " hardly moves";
    EXPECT_GT(fast / slow, 1.6) << name;
    EXPECT_LT(fast / slow, 4.0) << name;
    // Smooth: no jumps (joint-space speed below ~20 rad/s over all 20 angles) and bounded
    // acceleration (a kink or a restart would show as a large second difference).
    for (int i = 1; i < 299; ++i) {
      EXPECT_LT(mean_speed(cam, global, i, i + 1), 0.35) << name << " jumps at frame " << i;
      const auto q0 = cam.pose(i - 1).to_params(), q1 = cam.pose(i).to_params(), q2 = cam.pose(i + 1).to_params();
      EXPECT_LT((q2.tail<20>() - 2 * q1.tail<20>() + q0.tail<20>()).norm(), 0.1) << name << " frame " << i;
      EXPECT_LT((q2.head<3>() - 2 * q1.head<3>() + q0.head<3>()).norm(), 1.0) << name << " frame " << i;
    }
  }
  SyntheticCamera cam(clean_options("flexex1"));
  // Warped time: slope 1 early, 2.5 late (60 fps).
  const Motion m("flexex1", 300, 60.0, cam.shape());
  EXPECT_NEAR(m.motion_time(60) - m.motion_time(59), 1.0 / 60.0, 1e-9);
  EXPECT_NEAR(m.motion_time(260) - m.motion_time(259), kFastSpeedFactor / 60.0, 1e-9);
}

TEST(SynthMotions, PinchBringsTheThumbTipToTheIndexTip) {
  for (double scale : {0.9, 1.0, 1.1}) {
    SynthOptions o = clean_options("pinch");
    o.subject = SubjectScale{scale, 2.0 - scale};
    SyntheticCamera cam(o);
    const double contact = cam.shape().fingers[handtrack::kThumb].radius_mm[3] +
                           cam.shape().fingers[handtrack::kIndex].radius_mm[3];
    double closest = 1e9, farthest = 0;
    for (int i = 0; i < 300; ++i) {
      const Joints j = camera_frame_joints(cam.shape(), cam.pose(i));
      const double d = (j[static_cast<size_t>(handtrack::fingertip_joint(handtrack::kThumb))] -
                        j[static_cast<size_t>(handtrack::fingertip_joint(handtrack::kIndex))])
                           .norm();
      closest = std::min(closest, d);
      farthest = std::max(farthest, d);
    }
    EXPECT_NEAR(closest, contact, 2.0) << "scale " << scale;
    EXPECT_GT(farthest, 60.0) << "the pinch never opens";
  }
}

TEST(SynthKinematics, FollowsTheSkeletonDefinition) {
  const HandShape shape = HandShape::mean_adult();
  HandPose pose;
  // r = 0: palm toward the camera (z_h -> -z), fingers up (y_h -> -y), thumb toward +x.
  pose.translation_mm = Eigen::Vector3d(0, 0, 400);
  const Joints j = camera_frame_joints(shape, pose);
  const auto mid_tip = j[static_cast<size_t>(handtrack::fingertip_joint(handtrack::kMiddle))];
  EXPECT_NEAR(mid_tip.x(), 4.0, 1e-9);
  EXPECT_NEAR(mid_tip.y(), -(94.0 + 46 + 28 + 18), 1e-9);
  EXPECT_NEAR(mid_tip.z(), 400.0, 1e-9);
  EXPECT_GT(j[static_cast<size_t>(handtrack::fingertip_joint(handtrack::kThumb))].x(), 50.0);
  // Positive flexion bends toward the palm normal, i.e. toward the camera at r = 0;
  // positive MCP flexion of 90 deg points the middle finger's bones along z_h.
  pose.fingers[handtrack::kMiddle] = {0.0, std::numbers::pi / 2, 0.0, 0.0};
  const Joints k = hand_frame_joints(shape, pose);
  const Eigen::Vector3d dir = (k[static_cast<size_t>(handtrack::joint_index(handtrack::kMiddle, 1))] -
                               k[static_cast<size_t>(handtrack::joint_index(handtrack::kMiddle, 0))]) /
                              46.0;
  EXPECT_NEAR(dir.z(), 1.0, 1e-9);
  // Abduction first (about n), then flexion about the rotated axis: abd then 90 deg flex still
  // points along n = z_h.
  pose.fingers[handtrack::kMiddle] = {0.3, std::numbers::pi / 2, 0.0, 0.0};
  const Joints l = hand_frame_joints(shape, pose);
  const Eigen::Vector3d dir2 = (l[static_cast<size_t>(handtrack::joint_index(handtrack::kMiddle, 1))] -
                                l[static_cast<size_t>(handtrack::joint_index(handtrack::kMiddle, 0))]) /
                               46.0;
  EXPECT_NEAR(dir2.z(), 1.0, 1e-9);
  // Params round trip.
  pose.rotation = Eigen::Vector3d(0.1, -0.2, 0.3);
  const HandPose back = HandPose::from_params(pose.to_params());
  EXPECT_EQ(back.to_params(), pose.to_params());
}

// CPU time of this thread: the suite shares the machine with other jobs, and wall time would
// measure them too.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

TEST(SynthCamera, RendersA320x240FrameInAFewMilliseconds) {
  SynthOptions o = clean_options("random");
  o.noise = true;
  SyntheticCamera cam(o);
  SynthFrame f;
  cam.render(0, f);
  std::vector<double> ms;
  for (int i = 0; i < 120; ++i) {
    const double start = thread_cpu_ms();
    cam.render(i, f);
    ms.push_back(thread_cpu_ms() - start);
  }
  std::sort(ms.begin(), ms.end());
  const double median = ms[ms.size() / 2];
  RecordProperty("render_ms_median", std::to_string(median));
  std::printf("render: median %.2f ms CPU per 320x240 frame (noise on, body background)\n", median);
#if defined(NDEBUG) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
  EXPECT_LT(median, 5.0);  // it is also the daemon's 60 fps live camera
#else
  EXPECT_LT(median, 50.0);
#endif
}

// A camera rolled about its optical axis (--roll): the ground truth turns with it, and the forearm,
// which comes up from the image bottom in the desk views, enters from the side the roll takes the
// bottom to (a quarter turn: the left); the hand stays the same size in the image.
TEST(SynthCamera, ARolledCameraTurnsTheHandAndItsForearmToAnotherEdge) {
  const auto render = [](double roll_deg) {
    SynthOptions o = clean_options("adbadd", Background::kNone);
    o.roll_deg = roll_deg;
    return SyntheticCamera(o).render(60);
  };
  const SynthFrame upright = render(0.0);
  const SynthFrame rolled = render(90.0);
  const Eigen::Matrix3d quarter = Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (size_t j = 0; j < upright.joints.size(); ++j) {
    EXPECT_LT((rolled.joints[j] - quarter * upright.joints[j]).norm(), 1e-6) << "joint " << j;
  }
  // Where the forearm (depth without a hand label) lies from the hand in the image, in px: the
  // centroids' offset, and the hand's pixel count.
  struct Layout {
    Eigen::Vector2d forearm_from_hand;
    int hand = 0;
  };
  const auto layout = [](const SynthFrame& f) {
    const int w = f.depth.width();
    Eigen::Vector2d hand_sum = Eigen::Vector2d::Zero();
    Eigen::Vector2d arm_sum = Eigen::Vector2d::Zero();
    int hand = 0, arm = 0;
    for (size_t k = 0; k < f.labels.pixels.size(); ++k) {
      if (f.depth.depth_mm[k] <= 0.0F) continue;
      const Eigen::Vector2d uv(static_cast<double>(k % static_cast<size_t>(w)), static_cast<double>(k / static_cast<size_t>(w)));
      if (f.labels.pixels[k] != 0) {
        hand_sum += uv;
        ++hand;
      } else {
        arm_sum += uv;
        ++arm;
      }
    }
    return Layout{arm_sum / std::max(arm, 1) - hand_sum / std::max(hand, 1), hand};
  };
  const Layout up = layout(upright);
  const Layout turned = layout(rolled);
  EXPECT_GT(up.forearm_from_hand.y(), 40.0) << "below the hand";
  EXPECT_LT(std::abs(up.forearm_from_hand.x()), 20.0);
  EXPECT_LT(turned.forearm_from_hand.x(), -40.0) << "left of the hand";
  EXPECT_LT(std::abs(turned.forearm_from_hand.y()), 20.0);
  EXPECT_NEAR(turned.hand, up.hand, 0.05 * up.hand);
}

TEST(SynthCamera, RejectsBadOptions) {
  SynthOptions o;
  o.motion = "moonwalk";
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o = SynthOptions{};
  o.frames = 0;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o = SynthOptions{};
  o.camera.fx = 0;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o = SynthOptions{};
  o.subject = SubjectScale{3.0, 1.0};
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o.subject = SubjectScale{};
  o.subject->finger_length[handtrack::kRing] = 0.2;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o.subject = SubjectScale{};
  o.subject->palm_thickness = std::nan("");
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o = SynthOptions{};
  for (double arch : {-1.0, 21.0, std::nan("")}) {
    o.palm_arch_mm = arch;
    EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument) << "palm arch " << arch;
  }
  o = SynthOptions{};
  o.roll_deg = 181.0;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o.roll_deg = 90.0;
  EXPECT_NO_THROW(SyntheticCamera{o});
  o.background = Background::kDesk;  // placed in the camera's frame: not rolled
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o.background = Background::kBody;
  o.arm = Arm::kShoulder;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o.arm = Arm::kForearm;
  o.motion = "two_apart";
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
}

}  // namespace

// The generator and the tracker implement the same skeleton separately (module brief); at random
// poses within the limits, both must put all 21 joints of the mean adult hand at the same place.
#include "handtrack/core/kinematics.hpp"

namespace {

TEST(SynthKinematics, AgreesWithTheTrackersSkeleton) {
  const JointLimits limits = JointLimits::defaults();
  Rng rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    // A third of the trials with a scaled subject: both sides scale lengths by `length` and base
    // offsets across the hand by `width`.
    const SubjectScale subject = trial % 3 == 0 ? SubjectScale{} : SubjectScale{rng.uniform(0.9, 1.1), rng.uniform(0.9, 1.1)};
    const handtrack::HandModel model = handtrack::HandModel::default_adult({subject.length, subject.width, 1.0});
    const HandShape shape = HandShape::for_subject(subject);
    HandPose pose;
    pose.translation_mm = Eigen::Vector3d(rng.uniform(-50, 50), rng.uniform(-50, 50), rng.uniform(300, 500));
    pose.rotation = Eigen::Vector3d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    for (size_t f = 0; f < kNumFingers; ++f) {
      for (size_t k = 0; k < 4; ++k) pose.fingers[f][k] = rng.uniform(limits.lower[f][k], limits.upper[f][k]);
    }
    const Joints ours = camera_frame_joints(shape, pose);
    const handtrack::PosedHand theirs(model, pose.to_params());
    for (int j = 0; j < handtrack::kNumJoints; ++j) {
      EXPECT_LT((ours[static_cast<size_t>(j)] - theirs.joints()[static_cast<size_t>(j)]).norm(), 1e-6)
          << "joint " << handtrack::joint_name(j) << ", trial " << trial;
    }
  }
}

}  // namespace

// A left hand is the right hand's mirror image about the camera's x = 0 plane
// (synthetic_camera.hpp, Handedness): its joints are the right hand's with x negated, and its
// image is exactly the right hand's, rendered with the principal point mirrored, flipped left to
// right; everything else (subject, motion, noise) is the same.
TEST(SynthCamera, ALeftHandIsTheExactMirrorImageOfTheRightHand) {
  handtrack::synth::SynthOptions left;
  left.motion = "pinch";
  left.frames = 60;
  left.seed = 3;
  left.noise = false;
  left.hand = handtrack::synth::Handedness::kLeft;
  handtrack::synth::SynthOptions right = left;
  right.hand = handtrack::synth::Handedness::kRight;
  right.camera.cx = static_cast<double>(right.camera.width - 1) - left.camera.cx;
  handtrack::synth::SyntheticCamera left_cam(left);
  handtrack::synth::SyntheticCamera right_cam(right);
  EXPECT_EQ(left_cam.camera().cx, left.camera.cx) << "the left hand's sequence keeps the camera asked for";
  for (const int i : {0, 25, 50}) {
    const auto l = left_cam.render(i);
    const auto r = right_cam.render(i);
    for (size_t j = 0; j < l.joints.size(); ++j) {
      EXPECT_DOUBLE_EQ(l.joints[j].x(), -r.joints[j].x());
      EXPECT_DOUBLE_EQ(l.joints[j].y(), r.joints[j].y());
      EXPECT_DOUBLE_EQ(l.joints[j].z(), r.joints[j].z());
    }
    const int w = l.depth.camera.width;
    int hand_pixels = 0;
    for (int v = 0; v < l.depth.camera.height; ++v) {
      for (int u = 0; u < w; ++u) {
        const size_t a = static_cast<size_t>(v * w + u);
        const size_t b = static_cast<size_t>(v * w + (w - 1 - u));
        ASSERT_EQ(l.depth.depth_mm[a], r.depth.depth_mm[b]) << "frame " << i << " pixel " << u << "," << v;
        ASSERT_EQ(l.labels.pixels[a], r.labels.pixels[b]);
        hand_pixels += l.labels.pixels[a] != 0 ? 1 : 0;
      }
    }
    EXPECT_GT(hand_pixels, 500) << "a hand in view";
    // The left thumb tip projects through the left camera onto the hand in the left image.
    const Eigen::Vector2d uv = l.depth.camera.project(*l.fingertips[0]);
    EXPECT_NE(l.labels.pixels[static_cast<size_t>(std::lround(uv.y())) * static_cast<size_t>(w) +
                              static_cast<size_t>(std::lround(uv.x()))],
              0)
        << "frame " << i;
  }
}

namespace {

// The palm's normal from the ground-truth joints: wrist -> index MCP crossed with wrist -> little
// MCP points out of the palm of a right hand.
Eigen::Vector3d palm_normal(const Joints& j) {
  const Eigen::Vector3d& wrist = j[handtrack::kWristJoint];
  const Eigen::Vector3d index = j[handtrack::joint_index(1, 0)] - wrist;
  const Eigen::Vector3d little = j[handtrack::joint_index(4, 0)] - wrist;
  return index.cross(little).normalized();
}

// Every view shows the hand in the working volume, turned as its name says: the palm toward the
// camera (normal z < 0) in palm, away in back and head-mounted, edge-on in side; fingers nearer
// than the wrist with fingers-toward and farther with fingers-away and head-mounted; and a
// head-mounted forearm comes up from the image bottom (its lower third) nearer than the
// wrist.
TEST(SynthViews, EachViewTurnsThePoseAsItsNameSays) {
  const auto render = [](View view, int frame) {
    SynthOptions o = clean_options("adbadd");
    o.view = view;
    return SyntheticCamera(o).render(frame);
  };
  for (const int i : {0, 100, 250}) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const SynthFrame palm = render(View::kPalm, i);
    EXPECT_LT(palm_normal(palm.joints).z(), -0.7);
    EXPECT_GT(palm_normal(render(View::kBack, i).joints).z(), 0.7);
    EXPECT_LT(std::abs(palm_normal(render(View::kSide, i).joints).z()), 0.5);
    const auto finger_dz = [](const SynthFrame& f) {
      return f.joints[handtrack::fingertip_joint(2)].z() - f.joints[handtrack::kWristJoint].z();
    };
    EXPECT_LT(finger_dz(render(View::kFingersToward, i)), finger_dz(palm) - 60.0);
    EXPECT_GT(finger_dz(render(View::kFingersAway, i)), finger_dz(palm) + 60.0);
    const SynthFrame head = render(View::kHeadMounted, i);
    EXPECT_GT(palm_normal(head.joints).z(), 0.2);
    EXPECT_GT(finger_dz(head), 80.0);
    const auto& cam = head.depth.camera;
    int near_bottom = 0;
    for (int v = cam.height - cam.height / 3; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const float z = head.depth.depth_mm[static_cast<size_t>(v) * cam.width + u];
        near_bottom += z > 0.0F && z < head.joints[handtrack::kWristJoint].z() ? 1 : 0;
      }
    }
    // (From the motion's start: adbadd later rolls the hand far about the viewing axis, which a
    // view keeps, and the forearm with it.)
    if (i == 0) {
      EXPECT_GT(near_bottom, 200) << "the forearm comes from below, nearer than the wrist";
    }
    for (View v : kViews) {
      const SynthFrame f = render(v, i);
      int hand_pixels = 0;
      for (size_t k = 0; k < f.labels.pixels.size(); ++k) {
        hand_pixels += f.labels.pixels[k] != 0 && f.depth.depth_mm[k] >= 150.0F && f.depth.depth_mm[k] <= 600.0F;
      }
      EXPECT_GT(hand_pixels, 300) << view_name(v) << ": a hand in the working volume";
    }
  }
  EXPECT_EQ(render(View::kPalm, 40).depth.depth_mm, SyntheticCamera(clean_options("adbadd")).render(40).depth.depth_mm);
  for (View v : kViews) EXPECT_EQ(parse_view(view_name(v)), v);
  EXPECT_FALSE(parse_view("top"));
}

// A head-mounted camera sees the forearm come up from the image bottom, as a real one does, and
// never in front of the hand or at the lens, whatever a motion does with the hand: in every 10th
// frame of every motion, for three subjects, the bottom row shows the forearm, the hand keeps 700
// pixels (a hand at 330 mm has 1,000-3,000) and no pixel of the forearm is nearer than 120 mm.
// (Rigid in the hand frame, the forearm pointed at the lens as the motions rolled the hand, and
// hid the hand, or the whole image, at the ends of sequences: views.hpp, view_shape.)
TEST(SynthViews, AHeadMountedForearmComesFromTheImageBottomAndNeverHidesTheHand) {
  for (const std::string_view motion : kMotionNames) {
    for (const uint64_t seed : {1, 2, 3}) {
      SynthOptions o = clean_options(std::string(motion), Background::kTable);
      o.view = View::kHeadMounted;
      o.seed = seed;
      o.noise_params.min_range_mm = 1.0;  // the forearm wherever it is
      SyntheticCamera cam(o);
      for (int i = 0; i < o.frames; i += 10) {
        SCOPED_TRACE(std::string(motion) + " seed " + std::to_string(seed) + " frame " + std::to_string(i));
        const SynthFrame f = cam.render(i);
        const int w = f.depth.width();
        const double wrist_z = f.joints[handtrack::kWristJoint].z();
        int hand = 0;
        int forearm_at_bottom = 0;
        float nearest_forearm = std::numeric_limits<float>::infinity();
        for (size_t k = 0; k < f.labels.pixels.size(); ++k) {
          const float z = f.depth.depth_mm[k];
          if (z <= 0.0F) continue;
          if (f.labels.pixels[k] != 0) {
            ++hand;
          } else if (z < wrist_z) {  // nearer than the wrist: the forearm, not the table
            nearest_forearm = std::min(nearest_forearm, z);
            forearm_at_bottom += k >= f.labels.pixels.size() - static_cast<size_t>(w) ? 1 : 0;
          }
        }
        EXPECT_GE(hand, 700) << "the hand is in view";
        EXPECT_GE(forearm_at_bottom, 30) << "the forearm comes up from the image bottom";
        EXPECT_GE(nearest_forearm, 120.0F) << "the forearm stays away from the lens";
      }
    }
  }
}

}  // namespace

// Two hands at once (issue 14): a right and a left hand in one z-buffered image, each with its own
// subject and ground truth that agrees with the pixels.
namespace {

using handtrack::kThumb;
using handtrack::kLittle;

// Hand k's solids as the camera sees them (hand 1 is the mirror image of the model in its pose).
std::vector<ConeSphere> camera_solids(const SyntheticCamera& cam, int frame, int hand) {
  const HandPose pose = cam.pose(frame, hand);
  std::vector<ConeSphere> solids;
  posed_primitives(cam.shape(hand), pose, camera_frame_joints(cam.shape(hand), pose), solids);
  if (hand == 1) mirror_x(solids);
  return solids;
}

TEST(SynthGeometry, SurfaceGapOfConeSpheres) {
  // Spheres 30 mm apart, radii 10 and 5: 15 mm between the surfaces.
  const ConeSphere a{{0, 0, 400}, {0, 0, 400}, 10.0, 10.0, 0};
  const ConeSphere b{{30, 0, 400}, {30, 0, 400}, 5.0, 5.0, 0};
  EXPECT_NEAR(surface_gap_mm(a, b), 15.0, 1e-3);
  // A tapered capsule along x (radius 4 -> 12 over 100 mm) and a sphere above its middle: the
  // nearest ball is not under the sphere's centre, so the gap is below 40 - 8 - 5 = 27 mm:
  // min_s sqrt((100 s - 50)^2 + 40^2) - (4 + 8 s) - 5, solved numerically below.
  const ConeSphere cone{{0, 0, 0}, {100, 0, 0}, 4.0, 12.0, 0};
  const ConeSphere above{{50, 40, 0}, {50, 40, 0}, 5.0, 5.0, 0};
  double expected = 1e9;
  for (int i = 0; i <= 100000; ++i) {
    const double s = i / 100000.0;
    expected = std::min(expected, std::hypot(100 * s - 50, 40.0) - (4 + 8 * s) - 5);
  }
  EXPECT_LT(expected, 26.9);
  EXPECT_NEAR(surface_gap_mm(cone, above), expected, 1e-3);
  // Crossing capsules overlap: minus the deepest overlap of their balls (radius 6 + 6 at one point).
  const ConeSphere x{{-50, 0, 0}, {50, 0, 0}, 6.0, 6.0, 0};
  const ConeSphere y{{0, -50, 3}, {0, 50, 3}, 6.0, 6.0, 0};
  EXPECT_NEAR(surface_gap_mm(x, y), 3.0 - 12.0, 1e-3);
  EXPECT_NEAR(surface_gap_mm(std::vector<ConeSphere>{a, x}, std::vector<ConeSphere>{b, y}), -9.0, 1e-3);
}

TEST(SynthTwoHands, EveryTwoHandMotionShowsARightAndALeftHandWhoseGroundTruthIsOnTheirPixels) {
  for (auto name : kTwoHandMotionNames) {
    SyntheticCamera cam(clean_options(std::string(name)));
    ASSERT_EQ(cam.hand_count(), 2);
    int tips = 0, on_own_distal = 0;
    for (int i : {0, 37, 75, 150, 220, 299}) {
      SCOPED_TRACE(std::string(name) + " frame " + std::to_string(i));
      const SynthFrame f = cam.render(i);
      ASSERT_EQ(f.hand_count, 2);
      EXPECT_EQ(f.hands[0].hand, Handedness::kRight);
      EXPECT_EQ(f.hands[1].hand, Handedness::kLeft);
      ASSERT_EQ(f.hand_index.pixels.size(), f.labels.pixels.size());
      // Both hands in view; labels 1..12 on both, and nothing but hands and their forearms indexed.
      std::array<int, 2> labelled{};
      for (size_t p = 0; p < f.labels.pixels.size(); ++p) {
        const int k = f.hand_index.pixels[p];
        ASSERT_LE(k, 2);
        ASSERT_LE(f.labels.pixels[p], handtrack::kNumPartLabels);
        if (f.labels.pixels[p] != 0) {
          ASSERT_GT(k, 0) << "a part label outside both hands";
          ++labelled[static_cast<size_t>(k - 1)];
        }
      }
      EXPECT_GT(labelled[0], 300);
      EXPECT_GT(labelled[1], 300);
      for (int k = 0; k < 2; ++k) {
        const SynthHand& hand = f.hands[static_cast<size_t>(k)];
        // The ground truth is the hand's own: its model's joints (mirrored for the left hand).
        Joints expected = camera_frame_joints(cam.shape(k), cam.pose(i, k));
        if (k == 1) mirror_x(expected);
        for (size_t j = 0; j < expected.size(); ++j) EXPECT_EQ(hand.joints[j], expected[j]);
        for (int finger = 0; finger < kNumFingers; ++finger) {
          const Eigen::Vector3d tip = *hand.fingertips[static_cast<size_t>(finger)];
          const int index = pixel_index(cam.camera(), cam.camera().project(tip));
          ASSERT_GE(index, 0) << "hand " << k << " finger " << finger << " outside the image";
          ++tips;
          const auto p = static_cast<size_t>(index);
          const double radius = cam.shape(k).fingers[static_cast<size_t>(finger)].radius_mm[3];
          // The tip sphere covers its centre's pixel, so something is seen there: the sphere's front
          // (tip z - radius), or a surface in front of it (the other hand, or its own fingers).
          ASSERT_GT(f.depth.depth_mm[p], 0.0F);
          EXPECT_LT(f.depth.depth_mm[p], tip.z() - radius + 1.5) << "hand " << k << " finger " << finger;
          if (f.hand_index.pixels[p] == k + 1 && f.labels.pixels[p] == handtrack::part_label(finger, 2)) {
            ++on_own_distal;
            // Seen from the side, the pixel shows the tip sphere's front; a distal bone pointing
            // away from the camera (a curled finger) may hide it behind the bone's own skin.
            const Eigen::Vector3d bone = (tip - hand.joints[handtrack::joint_index(finger, 2)]).normalized();
            if (std::abs(bone.dot(tip.normalized())) < 0.5) {
              EXPECT_NEAR(f.depth.depth_mm[p], tip.z() - radius, 1.5) << "hand " << k << " finger " << finger;
            }
          }
        }
      }
    }
    // Seen from behind with the fingers pointing away (two_reach, head-mounted), a tip hides behind
    // its own finger or the back of the hand more often.
    const int tenths = two_hand_view(name) == View::kHeadMounted ? 3 : 6;
    EXPECT_GT(on_own_distal, tips * tenths / 10) << name << ": most fingertips are seen on their own hand";
  }
}

TEST(SynthTwoHands, StayAtDeskDistancesWithinJointLimitsAndInTheImage) {
  const JointLimits limits = JointLimits::defaults();
  for (auto name : kTwoHandMotionNames) {
    SyntheticCamera cam(clean_options(std::string(name)));
    for (int i = 0; i < 600; i += 5) {
      for (int k = 0; k < 2; ++k) {
        const HandPose p = cam.pose(i, k);
        ASSERT_TRUE(limits.contains(p)) << name << " frame " << i;
        Eigen::Vector3d palm = p.translation_mm + camera_R_hand(p.rotation) * cam.shape(k).palm_centre_mm;
        if (k == 1) palm.x() = -palm.x();
        EXPECT_GT(palm.z(), 300.0) << name << " hand " << k << " frame " << i;
        EXPECT_LT(palm.z(), 550.0) << name << " hand " << k << " frame " << i;
        const Eigen::Vector2d uv = cam.camera().project(palm);
        EXPECT_TRUE(uv.x() > 0 && uv.x() < 320 && uv.y() > 0 && uv.y() < 240) << name << " palm leaves the image";
      }
    }
  }
}

// Mirror images have the other chirality: with both palms toward the camera (two_apart), the right
// hand's thumb is on the image's right of its little finger, the left hand's on the left. The
// right hand is on the image's left (a desk camera facing the user), each hand its own subject.
TEST(SynthTwoHands, TheLeftHandIsAMirroredHandWithItsOwnSubject) {
  SyntheticCamera cam(clean_options("two_apart"));
  for (int i : {0, 100, 250}) {
    const SynthFrame f = cam.render(i);
    const auto& right = f.hands[0];
    const auto& left = f.hands[1];
    EXPECT_GT(right.fingertips[kThumb]->x(), right.fingertips[kLittle]->x()) << "frame " << i;
    EXPECT_LT(left.fingertips[kThumb]->x(), left.fingertips[kLittle]->x()) << "frame " << i;
    const double apart = (left.joints[handtrack::joint_index(2, 0)] - right.joints[handtrack::joint_index(2, 0)]).x();
    EXPECT_GT(apart, 150.0) << "frame " << i;
    EXPECT_LT(apart, 250.0) << "frame " << i;
  }
  EXPECT_NE(cam.subject(0).length, cam.subject(1).length);
  for (int k = 0; k < 2; ++k) {
    EXPECT_GE(cam.subject(k).length, 0.9);
    EXPECT_LE(cam.subject(k).length, 1.1);
  }
  // Hand 0 is the subject a one-hand motion of the same seed has; frames are a function of
  // (options, frame).
  EXPECT_EQ(cam.subject(0).length, SyntheticCamera(clean_options("pinch")).subject().length);
  SynthOptions noisy = clean_options("two_apart");
  noisy.noise = true;
  SyntheticCamera a(noisy), b(noisy);
  (void)a.render(7);
  EXPECT_EQ(a.render(42).depth.depth_mm, b.render(42).depth.depth_mm);
  EXPECT_EQ(a.render(42).hand_index.pixels, b.render(42).hand_index.pixels);
  // A one-hand frame: one hand, the legacy fields its own, no hand index.
  const SynthFrame one = SyntheticCamera(clean_options("pinch")).render(5);
  EXPECT_EQ(one.hand_count, 1);
  EXPECT_EQ(one.hands[0].joints, one.joints);
  EXPECT_TRUE(one.hand_index.pixels.empty());
}

// two_cross: the right hand passes in front of the left, the two swap sides in the image, and the
// near hand hides part of the far one while they cross.
TEST(SynthTwoHands, InTwoCrossTheHandsSwapSidesAndTheNearOneHidesTheFarOne) {
  SyntheticCamera cam(clean_options("two_cross"));
  const auto centre_u = [&](const SynthHand& h) {
    return cam.camera().project(h.joints[handtrack::joint_index(2, 0)]).x();
  };
  bool swapped = false;
  int most_far_pixels = 0, fewest_far_pixels = 1 << 30;
  for (int i = 0; i < 300; i += 4) {
    const SynthFrame f = cam.render(i);
    if (i == 0) {
      EXPECT_LT(centre_u(f.hands[0]), centre_u(f.hands[1]) - 80) << "the right hand starts on the left";
    }
    swapped = swapped || centre_u(f.hands[0]) > centre_u(f.hands[1]) + 80;
    EXPECT_LT(f.hands[0].joints[0].z(), f.hands[1].joints[0].z() - 80) << "frame " << i;
    const int far_pixels = static_cast<int>(std::count(f.hand_index.pixels.begin(), f.hand_index.pixels.end(), 2));
    most_far_pixels = std::max(most_far_pixels, far_pixels);
    fewest_far_pixels = std::min(fewest_far_pixels, far_pixels);
  }
  EXPECT_TRUE(swapped) << "the hands never crossed";
  EXPECT_LT(fewest_far_pixels, most_far_pixels * 2 / 3) << "the near hand never hid the far one";
}

// two_reach: a head-mounted camera over both hands reaching forward. It sees both backs (each
// thumb on the side of its hand nearer the middle of the image: the right hand's on the left of its
// little finger, as two_apart shows the left hand's), the right hand on the image's right, each
// hand in full, and both forearms coming up from the image bottom, nearer than the wrists.
TEST(SynthTwoHands, InTwoReachAHeadsetSeesBothBacksWithTheRightHandOnTheRight) {
  for (const uint64_t seed : {1, 2, 3}) {
    SynthOptions o = clean_options("two_reach", Background::kTable);
    o.seed = seed;
    o.noise_params.min_range_mm = 1.0;  // the forearms wherever they are
    SyntheticCamera cam(o);
    EXPECT_EQ(two_hand_view("two_reach"), View::kHeadMounted);
    for (int i = 0; i < o.frames; i += 10) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " frame " + std::to_string(i));
      const SynthFrame f = cam.render(i);
      const auto& right = f.hands[0];
      const auto& left = f.hands[1];
      const auto u = [&](const Eigen::Vector3d& p) { return cam.camera().project(p).x(); };
      EXPECT_GT(u(right.joints[handtrack::joint_index(2, 0)]), u(left.joints[handtrack::joint_index(2, 0)]) + 80);
      EXPECT_LT(u(*right.fingertips[kThumb]), u(*right.fingertips[kLittle]));
      EXPECT_GT(u(*left.fingertips[kThumb]), u(*left.fingertips[kLittle]));
      const int w = f.depth.width();
      const double wrists_z = std::min(right.joints[handtrack::kWristJoint].z(), left.joints[handtrack::kWristJoint].z());
      std::array<int, 2> pixels{}, forearm_at_bottom{};
      for (size_t k = 0; k < f.hand_index.pixels.size(); ++k) {
        const float z = f.depth.depth_mm[k];
        if (z <= 0.0F) continue;
        const int hand = f.hand_index.pixels[k];
        if (hand > 0 && f.labels.pixels[k] != 0) ++pixels[static_cast<size_t>(hand - 1)];
        const bool bottom = k >= f.hand_index.pixels.size() - static_cast<size_t>(w);
        if (bottom && f.labels.pixels[k] == 0 && z < wrists_z) {
          ++forearm_at_bottom[static_cast<int>(k % static_cast<size_t>(w)) < w / 2 ? 1 : 0];
        }
      }
      for (size_t k = 0; k < 2; ++k) {
        EXPECT_GE(pixels[k], 700) << "hand " << k << " is in view";
        EXPECT_GE(forearm_at_bottom[k], 20) << "hand " << k << "'s forearm comes up from the image bottom";
      }
    }
  }
}

// Each motion over the background its camera looks at, in handtrack-synth and in handtrackd's
// synthetic source alike: a head-mounted camera (two_reach's) a table, a camera facing the user the
// body.
TEST(SynthBackgrounds, EachScenesCameraLooksAtItsOwnBackground) {
  EXPECT_EQ(default_background("pinch", View::kHeadMounted), Background::kTable);
  EXPECT_EQ(default_background("pinch", View::kBack), Background::kBody);
  EXPECT_EQ(live_camera_options("two_reach", 300, 1, 60).background, Background::kTable);
  EXPECT_EQ(live_camera_options("two_apart", 300, 1, 60).background, Background::kBody);
  EXPECT_EQ(live_camera_options("flexex1", 300, 1, 60).background, Background::kBody);
}

// Hands may touch (two_clap: the palms meet) but never pass through each other; apart they stay
// apart.
TEST(SynthTwoHands, HandsTouchButNeverPassThroughEachOther) {
  for (auto name : kTwoHandMotionNames) {
    SyntheticCamera cam(clean_options(std::string(name)));
    double closest = 1e9, farthest = -1e9;
    for (int i = 0; i < 300; i += 3) {
      const double gap = surface_gap_mm(camera_solids(cam, i, 0), camera_solids(cam, i, 1));
      closest = std::min(closest, gap);
      farthest = std::max(farthest, gap);
    }
    std::printf("%s: hands %.1f to %.1f mm apart\n", std::string(name).c_str(), closest, farthest);
    EXPECT_GT(closest, -0.5) << name << ": the hands pass through each other";
    if (name == "two_clap") {
      EXPECT_LT(closest, 1.0) << "the palms never touch";
      EXPECT_GT(farthest, 80.0) << "the hands never part";
    }
    if (name == "two_apart") {
      EXPECT_GT(closest, 40.0);
    }
    if (name == "two_pinch") {
      EXPECT_GT(closest, 20.0);
    }
  }
}

TEST(SynthTwoHands, RejectsAHandOrViewAndSinglePoses) {
  SynthOptions o = clean_options("two_clap");
  o.hand = Handedness::kLeft;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  o = clean_options("two_clap");
  o.view = View::kBack;
  EXPECT_THROW(SyntheticCamera{o}, std::invalid_argument);
  SyntheticCamera cam(clean_options("two_pinch"));
  SynthFrame f;
  EXPECT_THROW(cam.render_pose(cam.pose(0), 0, f), std::logic_error);
  EXPECT_THROW((void)cam.pose(0, 2), std::out_of_range);
  EXPECT_TRUE(is_two_hand_motion("two_cross"));
  EXPECT_FALSE(is_two_hand_motion("pinch"));
}

}  // namespace
