#pragma once
// A body in the working volume (ours; the paper's scenes keep the body behind it, Sec. 4 segments
// the hand "from the rest of the body" by depth alone). A user who sits close, a camera looking
// down past the chest, a working volume deep enough for a hand at arm's length: the torso is then a
// surface of the volume, often nearer than the hand or joined to it through the arm, and the
// nearest sizeable surface is not the hand.
//
// No hand is wide: a disc of radius BodyEraser::kWideHandLengths hand lengths fits nowhere inside a
// hand's surface (the widest part of a hand, the palm or a fist, is about half a hand length
// across). Where such discs fit, the surface is a body: its *opening* by that disc (the union of
// every disc that fits inside it; Serra 1982, "Image analysis and mathematical morphology") is
// erased from the depth that segmentation looks at, like a desk (support_plane.hpp). What reaches
// out of the body narrower than the disc remains, as surfaces of their own: the arm and its hand,
// and the head, which is as wide as a hand and stays a candidate.
//
// The disc is measured in mm at each pixel's depth; distances are chamfer distances within the
// surface (chamfer.hpp), so an opening never spreads across an outline into another surface.
// Outside the image a surface goes on: a torso cut by the image's edge is as wide as it is. What is
// left of the surface and reaches less than the disc's radius beyond the opening is its outline
// (the discs' edges are not exact), and is erased with it.
// Private to core (HandSegmenter, HandSplitter); its scratch is reused from frame to frame.
#include "surfaces.hpp"

#include <cstddef>
#include <vector>

namespace handtrack {

class BodyEraser {
 public:
  BodyEraser();

  // The disc's radius in hand lengths (DepthInputConfig::hand_length_mm: 76 mm). The widest disc
  // inside a hand measured at most 49 mm (0.26 hand lengths) on the benchmark's renders (every view
  // and motion, seeds 1, 4 and 6, the forearm and the largest subjects included) and 31-48 mm on
  // the SR305 hands; on the SR305 frames a torso 92-126 mm, a head 42-48 mm (not wide).
  static constexpr double kWideHandLengths = 0.4;

  // Finds the opening of every surface c of `component` / `surfaces` (as label_surfaces() made them
  // from `depth_mm`) that is wider than a hand, of every surface or of those with eligible[c] != 0;
  // true when there is one. Frames with no surface of more area than the disc cost one pass over
  // the surfaces.
  bool find(const DepthInputConfig& config, const CameraIntrinsics& camera, const std::vector<float>& depth_mm,
            const std::vector<int>& component, const std::vector<Surface>& surfaces,
            const std::vector<uint8_t>* eligible = nullptr);
  // Room for an image of width x height (the whole image and its ring), so that find() never
  // allocates: its owner calls this on its first frame, since a body may first come into the
  // working volume long after start-up (the daemon's steady state allocates nothing).
  void reserve(int width, int height);
  // Sets the pixels of the openings find() found last to 0 (an image of the camera find() was
  // given); the caller labels the surfaces again.
  void erase(std::vector<float>& depth_mm) const;

 private:
  // Adds the pixels of surface `c`'s opening (within its pixel box) to opening_.
  void add_opening(const CameraIntrinsics& camera, double radius_mm, const std::vector<float>& depth_mm,
                   const std::vector<int>& component, int c, const PixelBox& box);

  std::vector<uint8_t> candidate_;  // per surface: eligible and of more area than the disc
  std::vector<PixelBox> boxes_;     // per surface: its pixels' box (candidates only)
  std::vector<int> grid_;           // the box plus a one-pixel ring: chamfer distances
  std::vector<ptrdiff_t> pixel_;    // per grid cell: its image index, -1 beyond the image
  std::vector<uint8_t> mine_;       // per grid cell: the surface's own
  std::vector<size_t> opening_;     // the openings' pixels (image indices)
  std::vector<size_t> part_;        // a part left of a surface (image indices)
  std::vector<int> stack_;          // its flood fill (grid cells)
};

}  // namespace handtrack
