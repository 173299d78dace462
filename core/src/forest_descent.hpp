#pragma once
// The part forest's descent (part_forest.hpp) eight pixels at a time in AVX2 registers: the
// scalar descent's arithmetic in 32-bit lanes, so the same leaves bit for bit. Private to core.
//
// A pixel's step down a node reads two probes, pixel (x, y) plus each offset turned and scaled by
// its 16.16 steps (probe_coordinate):
//   x' = x + ((u_x xx + u_y xy + 2^15) >> 16),   y' = y + ((u_x yx + u_y yy + 2^15) >> 16),
// clamped to the crop's background border, and goes right where d(u') - d(v') >= threshold. The
// scalar code takes the products in 64 bits (a step may be up to 2^22); with |u| <= 2^15 and every
// step within 2^14 each sum stays below 2^31, so 32-bit lanes give the same pixel. A step beyond
// 2^14 means a depth under 4 mm x (f / f_ref): such a batch is left to the scalar descent.
//
// Eight pixels per register gather their nodes and probes at once where the scalar loop issues one
// load after the other; the lanes still descend in lockstep, each group of eight fetching its next
// nodes (and a leaf once reached) while the other groups take their step.
#include "handtrack/core/part_forest.hpp"

#include <array>
#include <cstdint>

namespace handtrack {

inline constexpr int kDescentLanes = 32;  // pixels per batch, a multiple of 8

// A batch of pixels in crop coordinates with their probe steps (ProbeSteps), one array per field
// so that a register loads eight at once. Lanes from `count` up to the next multiple of 8 repeat
// the last pixel.
struct DescentLanes {
  alignas(32) std::array<int32_t, kDescentLanes> x{};
  alignas(32) std::array<int32_t, kDescentLanes> y{};
  alignas(32) std::array<int32_t, kDescentLanes> xx{};
  alignas(32) std::array<int32_t, kDescentLanes> xy{};
  alignas(32) std::array<int32_t, kDescentLanes> yx{};
  alignas(32) std::array<int32_t, kDescentLanes> yy{};
  int count = 0;
};

// The hand's depth the probes read: (width + 2) x (height + 2) floats, row-major, the box with a
// one-pixel background border (PartForest::Crop).
struct DescentCrop {
  const float* depth_mm = nullptr;
  int width = 0;
  int height = 0;
};

// Whether this CPU runs descend_avx2 (x86-64 with AVX2; never elsewhere).
bool avx2_descent_supported();

// Whether every step of the batch, the padding's included, is within 2^14: the batch descend_avx2
// may take (decided once a batch, for all the trees).
bool lanes_fit_avx2(const DescentLanes& lanes);

// Descends `tree` for the batch: at[p] is pixel p's leaf node (at: kDescentLanes entries, 32-byte
// aligned). Only where avx2_descent_supported() and lanes_fit_avx2(lanes).
void descend_avx2(const PartForestTree& tree, const DescentCrop& crop, const DescentLanes& lanes, uint32_t* at);

}  // namespace handtrack
