// The default hand model's palm (HandModel::default_adult): its surface reaches the knuckles, its
// thickness is a palm row's, and E_col counts the palm against the fingers as its rules say.
#include "handtrack/core/hand_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace handtrack {
namespace {

// The scales a user's profile may give (Sec. 6), the default first.
const std::vector<HandScale> kScales = {{1.0, 1.0, 1.0}, {1.1, 0.9, 1.05}, {0.9, 1.1, 0.95}};

std::vector<ModelGaussian> palm_of(const HandModel& model) {
  std::vector<ModelGaussian> palm;
  for (const ModelGaussian& g : model.gaussians()) {
    if (g.bone == kPalmBone) palm.push_back(g);
  }
  return palm;
}

// How far `point` (hand frame) lies into the surface of `palm`: the least distance to a palm
// Gaussian's mean in units of its sigma (<= 1: on or inside its 1-sigma sphere, the skin).
double palm_depth_in_sigmas(const std::vector<ModelGaussian>& palm, const Eigen::Vector3d& point) {
  double least = std::numeric_limits<double>::infinity();
  for (const ModelGaussian& g : palm) least = std::min(least, (point - g.palm_position).norm() / g.sigma_mm);
  return least;
}

// A hand seen from behind shows the knuckles most of all (docs/TRACKER.md, "Knuckles"): along each
// finger's line in the palm's plane, from the palm's middle to the finger's base, the palm's surface
// runs on with no gap (within 1.3 sigma of a palm Gaussian everywhere; the little finger's knuckle,
// sigma 8 mm, lies 10 mm from its base). Without the knuckles the rows ended 17 mm short: the index
// finger's base lay 1.55 sigma from the nearest row.
TEST(HandModel, ThePalmsSurfaceReachesEachFingersBase) {
  for (const HandScale& scale : kScales) {
    const HandModel model = HandModel::default_adult(scale);
    const std::vector<ModelGaussian> palm = palm_of(model);
    const double palm_middle_y = model.palm_centre().y();
    for (int f = kIndex; f <= kLittle; ++f) {
      const Eigen::Vector3d base = model.fingers()[static_cast<size_t>(f)].base;
      for (double y = palm_middle_y; y <= base.y(); y += 1.0) {
        const Eigen::Vector3d point(base.x(), y, 0.0);
        EXPECT_LE(palm_depth_in_sigmas(palm, point), 1.3)
            << kFingerNames[static_cast<size_t>(f)] << " at y = " << y << " mm, scale length " << scale.length;
      }
    }
  }
}

// The knuckles sit below the finger bases in the palm's plane and leave the palm's thickness (the
// start search places a hand's centre that far behind the surface it sees) to its rows: 13 mm.
TEST(HandModel, FourKnucklesBelowTheFingersAndThePalmsThicknessItsRows) {
  for (const HandScale& scale : kScales) {
    const HandModel model = HandModel::default_adult(scale);
    const std::vector<ModelGaussian> palm = palm_of(model);
    EXPECT_EQ(model.gaussians().size(), 43U);
    EXPECT_EQ(palm.size(), 13U);
    EXPECT_DOUBLE_EQ(model.palm_half_thickness_mm(), 13.0 * scale.sigma);
    for (int f = kIndex; f <= kLittle; ++f) {
      const Eigen::Vector3d base = model.fingers()[static_cast<size_t>(f)].base;
      const bool has_knuckle = std::any_of(palm.begin(), palm.end(), [&](const ModelGaussian& g) {
        const Eigen::Vector3d offset = base - g.palm_position;
        return g.palm_position.z() == 0.0 && std::abs(offset.x()) < 1e-9 && offset.y() > 5.0 && offset.y() < 15.0;
      });
      EXPECT_TRUE(has_knuckle) << kFingerNames[static_cast<size_t>(f)] << ": no palm Gaussian just below its base";
    }
  }
}

// E_col (Sec. 4.1): every palm Gaussian, the knuckles too, against every Gaussian of each finger's
// two outer bones (a fingertip must not sink into the palm), and none against a finger's first
// bone, which the palm overlaps by construction at every pose.
TEST(HandModel, ThePalmCollidesWithTheFingersOuterBonesOnly) {
  const HandModel model = HandModel::default_adult();
  const auto& gaussians = model.gaussians();
  const auto n = gaussians.size();
  std::vector<std::vector<bool>> paired(n, std::vector<bool>(n, false));
  for (const CollisionPair& p : model.collision_pairs()) {
    paired[static_cast<size_t>(p.a)][static_cast<size_t>(p.b)] = true;
    paired[static_cast<size_t>(p.b)][static_cast<size_t>(p.a)] = true;
  }
  for (size_t a = 0; a < n; ++a) {
    if (gaussians[a].bone != kPalmBone) continue;
    for (size_t b = 0; b < n; ++b) {
      const int bone = gaussians[b].bone;
      if (bone == kPalmBone) {
        EXPECT_FALSE(paired[a][b]) << "palm Gaussians " << a << " and " << b;
        continue;
      }
      const bool outer = bone % kBonesPerFinger != 0;
      EXPECT_EQ(paired[a][b], outer) << "palm Gaussian " << a << " and Gaussian " << b << " of bone " << bone;
    }
  }
}

}  // namespace
}  // namespace handtrack
