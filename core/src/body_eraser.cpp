#include "body_eraser.hpp"

#include "chamfer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace handtrack {

namespace {
// A chamfer distance no surface reaches (and that the transform's + 4 does not overflow).
constexpr int kFar = 1 << 28;
}  // namespace

BodyEraser::BodyEraser() {
  candidate_.reserve(kReservedSurfaces);
  boxes_.reserve(kReservedSurfaces);
}

bool BodyEraser::find(const DepthInputConfig& config, const CameraIntrinsics& camera,
                      const std::vector<float>& depth_mm, const std::vector<int>& component,
                      const std::vector<Surface>& surfaces, const std::vector<uint8_t>* eligible) {
  const int w = camera.width;
  const int h = camera.height;
  const double radius_mm = kWideHandLengths * config.hand_length_mm;
  // A surface of less area than the disc cannot hold it: most frames stop here.
  const double disc_mm2 = std::numbers::pi * radius_mm * radius_mm;
  opening_.clear();
  candidate_.assign(surfaces.size(), 0);
  bool any = false;
  for (size_t c = 0; c < surfaces.size(); ++c) {
    candidate_[c] = (eligible == nullptr || (c < eligible->size() && (*eligible)[c] != 0)) &&
                    surface_area_mm2(camera, surfaces[c].pixels, surfaces[c].mean_depth()) >= disc_mm2;
    any = any || candidate_[c] != 0;
  }
  if (!any) return false;
  reserve(w, h);  // nothing where the owner did (on its first frame)
  boxes_.assign(surfaces.size(), PixelBox{w, h, -1, -1});
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const int c = component[static_cast<size_t>(v) * w + u];
      if (c >= 0 && candidate_[static_cast<size_t>(c)] != 0) boxes_[static_cast<size_t>(c)].add(u, v);
    }
  }
  for (size_t c = 0; c < surfaces.size(); ++c) {
    if (candidate_[c] != 0) add_opening(camera, radius_mm, depth_mm, component, static_cast<int>(c), boxes_[c]);
  }
  return !opening_.empty();
}

void BodyEraser::reserve(int width, int height) {
  // The largest box: the whole image and its ring.
  const auto most_cells = static_cast<size_t>(std::max(width, 0) + 2) * static_cast<size_t>(std::max(height, 0) + 2);
  if (grid_.capacity() >= most_cells) return;
  grid_.reserve(most_cells);
  pixel_.reserve(most_cells);
  mine_.reserve(most_cells);
  stack_.reserve(most_cells);  // flood4 pushes a cell once
  opening_.reserve(most_cells);
  part_.reserve(most_cells);
}

void BodyEraser::erase(std::vector<float>& depth_mm) const {
  for (const size_t i : opening_) depth_mm[i] = 0.0F;
}

void BodyEraser::add_opening(const CameraIntrinsics& camera, double radius_mm, const std::vector<float>& depth_mm,
                             const std::vector<int>& component, int c, const PixelBox& box) {
  const int w = camera.width;
  const int h = camera.height;
  // The box with a one-pixel ring: cell (x, y) is pixel (u0 - 1 + x, v0 - 1 + y); index -1 for a
  // cell beyond the image.
  const int gw = box.u1 - box.u0 + 3;
  const int gh = box.v1 - box.v0 + 3;
  const size_t cells = static_cast<size_t>(gw) * static_cast<size_t>(gh);
  pixel_.resize(cells);
  for (int y = 0; y < gh; ++y) {
    const int v = box.v0 - 1 + y;
    for (int x = 0; x < gw; ++x) {
      const int u = box.u0 - 1 + x;
      const bool in_image = u >= 0 && v >= 0 && u < w && v < h;
      pixel_[static_cast<size_t>(y) * gw + x] = in_image ? static_cast<ptrdiff_t>(v) * w + u : -1;
    }
  }
  // Whose cell: the surface's (open to the transforms), another's (its outline), beyond the image.
  std::vector<uint8_t>& mine = mine_;
  mine.resize(cells);
  grid_.resize(cells);
  for (size_t k = 0; k < cells; ++k) {
    const ptrdiff_t i = pixel_[k];
    mine[k] = i >= 0 && component[static_cast<size_t>(i)] == c ? 1 : 0;
    // The distance to the outline: 0 on it; beyond the image the surface goes on.
    grid_[k] = mine[k] != 0 || i < 0 ? kFar : 0;
  }
  const auto open = [&](size_t k) { return mine[k] != 0; };
  chamfer_transform(grid_, gw, gh, kFar, open);
  // The discs' centres: farther from the outline than the disc's radius in pixels at their depth
  // (the transform counts 3 a pixel). Each starts a disc of that radius: -radius there, so that
  // the second transform leaves <= 0 on every cell within a disc.
  const double radius_px_mm = 3.0 * radius_mm * camera.focal();  // 3 x the radius in pixels x depth
  bool any = false;
  for (size_t k = 0; k < cells; ++k) {
    if (mine[k] == 0) {
      grid_[k] = kFar;  // a wall: the discs stay within the surface
      continue;
    }
    const double radius = radius_px_mm / depth_mm[static_cast<size_t>(pixel_[k])];
    const bool centre = grid_[k] > radius;
    grid_[k] = centre ? -static_cast<int>(std::lround(radius)) : kFar;
    any = any || centre;
  }
  if (!any) return;
  chamfer_transform(grid_, gw, gh, kFar, open);
  // Now > 0 only outside the opening: a third of a pixel for each step beyond it.
  for (size_t k = 0; k < cells; ++k) {
    if (mine[k] != 0 && grid_[k] <= 0) opening_.push_back(static_cast<size_t>(pixel_[k]));
  }
  // What is left reaches out of the opening: an arm, a head, or outline the discs just missed
  // (chamfer lengths are 8 % off, and a disc's size follows its centre's depth, not the outline's).
  // A part that reaches less than the disc's radius beyond the opening is outline: erased too.
  for (size_t seed = 0; seed < cells; ++seed) {
    if (mine[seed] != 1 || grid_[seed] <= 0) continue;
    part_.clear();
    stack_.assign(1, static_cast<int>(seed));
    mine[seed] = 2;  // visited
    double reach_mm = 0.0;
    flood4(
        PixelBox{0, 0, gw - 1, gh - 1}, gw, stack_,
        [&](size_t j, size_t) {
          if (mine[j] != 1 || grid_[j] <= 0) return false;
          mine[j] = 2;
          return true;
        },
        [&](size_t k) {
          const auto i = static_cast<size_t>(pixel_[k]);
          part_.push_back(i);
          reach_mm = std::max(reach_mm, grid_[k] / 3.0 * depth_mm[i] / camera.focal());
        });
    if (reach_mm < radius_mm) opening_.insert(opening_.end(), part_.begin(), part_.end());
  }
}

}  // namespace handtrack
