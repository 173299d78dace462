#include "forest_descent.hpp"

#include <algorithm>
#include <cstdlib>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace handtrack {

#if defined(__x86_64__)

namespace {

// The largest step (16.16) whose probe sums stay within 32 bits: |u| <= 2^15, so each product is
// within 2^29 and the sum of two with the rounding half below 2^31 (forest_descent.hpp).
constexpr int32_t kMaxLaneStep = 1 << 14;

// A node as four 32-bit words: (u_x, u_y) as two int16, (v_x, v_y) likewise, the threshold, the
// child (part_forest.hpp's layout, checked there).
constexpr int kWordU = 0;
constexpr int kWordV = 1;
constexpr int kWordThreshold = 2;
constexpr int kWordChild = 3;
static_assert(sizeof(PartForestNode) == 4 * sizeof(int32_t));

// The batch's descent, a group of eight lanes a register (descend_avx2).
__attribute__((target("avx2"))) void descend8(const PartForestTree& tree, const DescentCrop& crop,
                                              const DescentLanes& lanes, uint32_t* at) {
  const auto* words = reinterpret_cast<const int32_t*>(tree.nodes.data());
  // One step of the eight pixels from lane `first` whose nodes are not all leaves: `node` their
  // node indices, `child` their nodes' child words. Returns the next node indices, leaves staying.
  const auto step8 = [&](int first, __m256i node, __m256i child) __attribute__((target("avx2"))) {
    const auto lane = [&](const std::array<int32_t, kDescentLanes>& field) __attribute__((target("avx2"))) {
      return _mm256_load_si256(reinterpret_cast<const __m256i*>(field.data() + first));
    };
    const __m256i x = lane(lanes.x);
    const __m256i y = lane(lanes.y);
    const __m256i xx = lane(lanes.xx);
    const __m256i xy = lane(lanes.xy);
    const __m256i yx = lane(lanes.yx);
    const __m256i yy = lane(lanes.yy);
    const __m256i one = _mm256_set1_epi32(1);
    const __m256i half = _mm256_set1_epi32(1 << (kProbeScaleBits - 1));
    const __m256i index = _mm256_slli_epi32(node, 2);
    // d(x + offset): the offset's int16 pair from its word, turned and scaled, rounded, clamped to
    // the border, read.
    const auto probe = [&](int word) __attribute__((target("avx2"))) {
      const __m256i packed = _mm256_i32gather_epi32(words + word, index, 4);
      const __m256i ox = _mm256_srai_epi32(_mm256_slli_epi32(packed, 16), 16);
      const __m256i oy = _mm256_srai_epi32(packed, 16);
      const auto along = [&](__m256i c, __m256i kx, __m256i ky, int size) __attribute__((target("avx2"))) {
        const __m256i sum = _mm256_add_epi32(_mm256_add_epi32(_mm256_mullo_epi32(ox, kx), _mm256_mullo_epi32(oy, ky)), half);
        const __m256i moved = _mm256_add_epi32(c, _mm256_srai_epi32(sum, kProbeScaleBits));
        return _mm256_min_epi32(_mm256_max_epi32(moved, _mm256_set1_epi32(-1)), _mm256_set1_epi32(size));
      };
      const __m256i px = along(x, xx, xy, crop.width);
      const __m256i py = along(y, yx, yy, crop.height);
      const __m256i i = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_add_epi32(py, one), _mm256_set1_epi32(crop.width + 2)),
                                         _mm256_add_epi32(px, one));
      return _mm256_i32gather_ps(crop.depth_mm, i, 4);
    };
    const __m256 difference = _mm256_sub_ps(probe(kWordU), probe(kWordV));
    const __m256 threshold = _mm256_i32gather_ps(reinterpret_cast<const float*>(words) + kWordThreshold, index, 4);
    // child + 1, less 1 (all ones) where the difference is below the threshold: left.
    const __m256 left = _mm256_cmp_ps(difference, threshold, _CMP_LT_OQ);
    const __m256i next = _mm256_add_epi32(_mm256_add_epi32(child, one), _mm256_castps_si256(left));
    return _mm256_blendv_epi8(next, node, _mm256_srai_epi32(child, 31));  // a leaf (child's top bit) stays
  };

  const int groups = (lanes.count + 7) / 8;
  std::array<int, kDescentLanes / 8> arrived{};  // per group, a bit per lane: on its leaf
  for (int p = 0; p < 8 * groups; ++p) at[p] = 0;
  for (bool descending = true; descending;) {
    descending = false;
    for (int g = 0; g < groups; ++g) {
      auto& done = arrived[static_cast<size_t>(g)];
      if (done == 0xff) continue;
      auto* group = reinterpret_cast<__m256i*>(at + 8 * g);
      const __m256i node = _mm256_load_si256(group);
      const __m256i child = _mm256_i32gather_epi32(words + kWordChild, _mm256_slli_epi32(node, 2), 4);
      const int leaf = _mm256_movemask_ps(_mm256_castsi256_ps(child));
      if (int fresh = leaf & ~done; fresh != 0) {
        // The leaves just reached are read after the descent: fetch them now (a leaf's 26 bytes
        // may straddle two cache lines).
        alignas(32) std::array<uint32_t, 8> children{};
        _mm256_store_si256(reinterpret_cast<__m256i*>(children.data()), child);
        for (; fresh != 0; fresh &= fresh - 1) {
          const uint32_t c = children[static_cast<size_t>(__builtin_ctz(static_cast<unsigned>(fresh)))];
          const auto* l = reinterpret_cast<const char*>(tree.leaves.data() + (c & ~PartForestNode::kLeafBit));
          __builtin_prefetch(l);
          __builtin_prefetch(l + sizeof(PartForestLeaf) - 1);
        }
      }
      done = leaf;
      if (leaf == 0xff) continue;
      descending = true;
      _mm256_store_si256(group, step8(8 * g, node, child));
      // Each lane's next node is needed only after the other groups' steps: fetch it now.
      for (int k = 0; k < 8; ++k) __builtin_prefetch(tree.nodes.data() + at[8 * g + k]);
    }
  }
}

}  // namespace

bool avx2_descent_supported() {
  static const bool supported = __builtin_cpu_supports("avx2");
  return supported;
}

bool lanes_fit_avx2(const DescentLanes& lanes) {
  const int n = (lanes.count + 7) / 8 * 8;
  int32_t largest = 0;
  for (int p = 0; p < n; ++p) {
    const auto q = static_cast<size_t>(p);
    for (const int32_t k : {lanes.xx[q], lanes.xy[q], lanes.yx[q], lanes.yy[q]}) largest = std::max(largest, std::abs(k));
  }
  return largest <= kMaxLaneStep;
}

void descend_avx2(const PartForestTree& tree, const DescentCrop& crop, const DescentLanes& lanes, uint32_t* at) {
  descend8(tree, crop, lanes, at);
}

#else

bool avx2_descent_supported() { return false; }

bool lanes_fit_avx2(const DescentLanes&) { return false; }

void descend_avx2(const PartForestTree&, const DescentCrop&, const DescentLanes&, uint32_t*) {}

#endif

}  // namespace handtrack
