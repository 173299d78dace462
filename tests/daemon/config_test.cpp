// handtrackd's configuration: the paper's values as defaults, the shipped file equal to them,
// every bad value refused with the file, the field and the range; and make_source's parsing.
#include "handtrack/daemon/config.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <vector>

namespace handtrack::daemon {
namespace {

std::string error_of(const std::string& toml) {
  try {
    (void)parse_config(toml, "test.toml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return {};
}

TEST(DaemonConfig, DefaultsAreThePapersValuesOrOursMeasured) {
  const DaemonConfig c;
  EXPECT_EQ(c.tracker.particles, 2);                     // Sec. 7
  EXPECT_EQ(c.tracker.optimizer.iterations, 10);         // Sec. 7
  EXPECT_DOUBLE_EQ(c.tracker.weights.collision, 1.0);    // w_c, Sec. 4.1
  EXPECT_DOUBLE_EQ(c.tracker.weights.tracking_collision, kMeasuredTrackingCollision);  // ours, measured
  EXPECT_DOUBLE_EQ(c.tracker.weights.limits, 0.2);       // w_l
  EXPECT_DOUBLE_EQ(c.tracker.weights.smoothness, kMeasuredSmoothness);  // w_s: ours, measured
  EXPECT_DOUBLE_EQ(c.tracker.weights.label_radius_mm, 200.0);  // R_i, Sec. 4.3
  EXPECT_DOUBLE_EQ(c.tracker.input.near_mm, 150.0);      // Sec. 4
  EXPECT_DOUBLE_EQ(c.tracker.input.far_mm, 600.0);
  EXPECT_DOUBLE_EQ(c.tracker.input.quadtree_threshold_mm, 20.0);  // epsilon_c, Sec. 3.1
  EXPECT_EQ(c.source, "openni2");
  EXPECT_EQ(c.shm_name, "handtrack");
}

TEST(DaemonConfig, ShippedFileEqualsTheDefaults) {
  const auto file = std::string(HANDTRACK_SOURCE_DIR) + "/data/handtrackd.toml";
  const DaemonConfig shipped = load_config(file, true);
  EXPECT_EQ(describe_config(shipped), describe_config(DaemonConfig{}));
  // And describe_config writes exactly the shipped file (regenerate with handtrackd --print-config).
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), describe_config(DaemonConfig{}));
}

TEST(DaemonConfig, ValuesOverrideDefaults) {
  const auto c = parse_config(
      "[daemon]\nsource = \"synthetic:pinch\"\nlog_level = \"debug\"\n"
      "[tracker]\nparticles = 1\narrangement = \"head-mounted\"\n[tracker.energy]\nw_s = 2.5\nw_c_tracking = 0.75\n[tracker.optimizer]\niterations = 20\n"
      "[tracker.input]\nfar_mm = 700\n[pipeline]\ncpu_optimize = 1\n",
      "x.toml");
  EXPECT_EQ(c.source, "synthetic:pinch");
  EXPECT_EQ(c.log_level, LogLevel::kDebug);
  EXPECT_EQ(c.tracker.particles, 1);
  EXPECT_EQ(c.tracker.arrangement, CameraArrangement::kHeadMounted);
  EXPECT_DOUBLE_EQ(c.tracker.weights.smoothness, 2.5);
  EXPECT_DOUBLE_EQ(c.tracker.weights.tracking_collision, 0.75);
  EXPECT_EQ(c.tracker.optimizer.iterations, 20);
  EXPECT_DOUBLE_EQ(c.tracker.input.far_mm, 700.0);  // an integer is a fine number
  EXPECT_EQ(c.pipeline.cpu[static_cast<size_t>(Stage::kOptimize)], 1);
  EXPECT_DOUBLE_EQ(c.tracker.weights.collision, 1.0);  // untouched
}

TEST(DaemonConfig, BadValuesNameFileFieldAndRange) {
  EXPECT_EQ(error_of("[tracker]\nparticles = 65\n"), "test.toml: tracker.particles = 65 is out of range (allowed range 1..64)");
  EXPECT_EQ(error_of("[tracker.energy]\nw_l = -0.1\n"),
            "test.toml: tracker.energy.w_l = -0.1 is out of range (allowed range 0.0..1000.0)");
  EXPECT_EQ(error_of("[tracker.energy]\nw_l = nan\n").rfind("test.toml: tracker.energy.w_l = nan is out of range", 0), 0U);
  EXPECT_EQ(error_of("[tracker]\nparticles = 1.5\n"),
            "test.toml: tracker.particles must be an integer (allowed range 1..64)");
  EXPECT_EQ(error_of("[daemon]\nfast = 1\n"), "test.toml: daemon.fast must be true or false");
  EXPECT_EQ(error_of("[tracker]\narrangement = \"desk\"\n").find("test.toml: tracker.arrangement"), 0U);
  EXPECT_EQ(error_of("[camera]\nroll = 45\n"), "test.toml: camera.roll = 45: allowed: 0, 90, 180, 270 (or -90, -180)");
  EXPECT_EQ(error_of("[camera]\nroll = 360\n"),
            "test.toml: camera.roll = 360 is out of range (allowed range -180..270)");
  EXPECT_EQ(error_of("[daemon]\nsource = \"\"\n"),
            "test.toml: daemon.source = '': allowed: a string of 1 to 4096 characters");
  EXPECT_NE(error_of("[nope]\nx = 1\n").find("unknown field 'nope.x'"), std::string::npos);
  EXPECT_NE(error_of("particles = 2\n").find("unknown field 'particles'"), std::string::npos);
  EXPECT_NE(error_of("[tracker]\nparticles = = 2\n").find("test.toml:2:"), std::string::npos);
  EXPECT_NE(error_of("[tracker.input]\nquadtree_min_leaf_px = 64\nquadtree_root_px = 16\n")
                .find("quadtree_min_leaf_px = 64 must not exceed"),
            std::string::npos);
}

TEST(DaemonConfig, MissingDefaultFileIsFineMissingExplicitFileIsNot) {
  EXPECT_NO_THROW((void)load_config("/nonexistent/handtrackd.toml", false));
  EXPECT_THROW((void)load_config("/nonexistent/handtrackd.toml", true), ConfigError);
}

TEST(DaemonConfig, HandProfileReplacesTheScaleAndABadOneIsRefusedNamingIt) {
  const std::string file = ::testing::TempDir() + "/config_test_profile.json";
  std::ofstream(file) << R"({"hand_length": 1.1, "hand_width": 0.95, "gaussian_sigma": 1.05})";
  const auto c = parse_config("[tracker]\nhand_profile = '" + file + "'\n", "test.toml");
  EXPECT_DOUBLE_EQ(c.tracker.scale.length, 1.1);
  EXPECT_DOUBLE_EQ(c.tracker.scale.width, 0.95);
  EXPECT_DOUBLE_EQ(c.tracker.scale.sigma, 1.05);
  std::ofstream(file) << R"({"hand_length": 1.1, "hand_width": 3, "gaussian_sigma": 1.05})";
  const auto e = error_of("[tracker]\nhand_profile = '" + file + "'\n");
  EXPECT_NE(e.find("test.toml"), std::string::npos) << e;
  EXPECT_NE(e.find("tracker.hand_profile"), std::string::npos) << e;
  EXPECT_NE(e.find("hand_width"), std::string::npos) << e;
  EXPECT_NE(error_of("[tracker]\nhand_profile = '/nonexistent/profile.json'\n").find("cannot open"), std::string::npos);
}

TEST(DaemonConfig, ReloadTellsWhichFieldsNeedARestart) {
  DaemonConfig a;
  DaemonConfig b;
  b.tracker.particles = 1;
  b.log_level = LogLevel::kDebug;
  EXPECT_TRUE(changed_but_not_live(a, b).empty());
  b.shm_name = "other";
  b.pipeline.queue_capacity = 3;
  EXPECT_EQ(changed_but_not_live(a, b), (std::vector<std::string>{"daemon.shm_name", "pipeline.queue_capacity"}));
}

TEST(MakeSource, RefusesMalformedSpecsNamingThem) {
  SourceOptions o;
  for (const std::string spec : {"webcam", "seq:", "oni:", "synthetic:", "synthetic:juggle", "openni2:"}) {
    try {
      (void)make_source(spec, o);
      ADD_FAILURE() << spec << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(spec.substr(0, spec.find(':'))), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(make_source("synthetic:pinch", o)->describe(), "synthetic:pinch");
  EXPECT_EQ(make_source("seq:/some/dir", o)->describe(), "seq:/some/dir");
  EXPECT_FALSE(make_source("synthetic", o)->is_live());
}

// Prerendered, the synthetic camera delivers the frames it renders live (the first period; the
// first frames of the next one are the period's first frames again).
TEST(MakeSource, PrerenderedSyntheticFramesAreTheLiveOnes) {
  SourceOptions live;
  live.as_fast_as_possible = true;
  live.synthetic_frames = 4;  // one motion: 0 1 2 3 2 1, then again
  SourceOptions stored = live;
  stored.synthetic_prerender = true;
  auto a = make_source("synthetic:two_apart", live);
  auto b = make_source("synthetic:two_apart", stored);
  ASSERT_TRUE(a->open(nullptr));
  ASSERT_TRUE(b->open(nullptr));
  std::vector<RawFrame> period;
  for (int i = 0; i < 8; ++i) {
    RawFrame fa;
    RawFrame fb;
    ASSERT_EQ(a->grab(fa, std::chrono::milliseconds(1000)), GrabStatus::kFrame);
    ASSERT_EQ(b->grab(fb, std::chrono::milliseconds(1000)), GrabStatus::kFrame);
    EXPECT_EQ(fb.frame_number, static_cast<uint64_t>(i));
    EXPECT_EQ(fb.camera.width, fa.camera.width);
    EXPECT_EQ(fb.camera.cx, fa.camera.cx);
    if (i < 6) {
      EXPECT_EQ(fb.depth_raw, fa.depth_raw) << "frame " << i;
      period.push_back(fb);
    } else {
      EXPECT_EQ(fb.depth_raw, period[static_cast<size_t>(i - 6)].depth_raw) << "frame " << i;
    }
  }
  EXPECT_NE(period[0].depth_raw, period[1].depth_raw);
}

TEST(MakeSource, RefusesAPrerenderTooLargeSayingHowMuch) {
  SourceOptions o;
  o.synthetic_prerender = true;
  o.synthetic_frames = 1'000'000;
  try {
    (void)make_source("synthetic:pinch", o);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("synthetic.prerender"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("MiB"), std::string::npos) << e.what();
  }
}

TEST(MakeSource, SequenceSourceReportsWhyItCannotOpen) {
  auto s = make_source("seq:/nonexistent/sequence", SourceOptions{});
  std::string why;
  EXPECT_FALSE(s->open(&why));
  EXPECT_NE(why.find("/nonexistent/sequence"), std::string::npos) << why;
}

}  // namespace
}  // namespace handtrack::daemon
