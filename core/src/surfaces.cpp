#include "surfaces.hpp"

#include <cmath>

namespace handtrack {

void label_surfaces(const DepthInputConfig& config, const std::vector<float>& d, int w, int h, std::vector<int>& component,
                    std::vector<int>& stack, std::vector<Surface>& surfaces) {
  const auto n = static_cast<size_t>(w) * h;
  component.assign(n, -1);
  surfaces.clear();
  // A surface per pixel at most, and the flood fill holds at most every pixel: no allocation once
  // a frame was seen.
  surfaces.reserve(n);
  stack.reserve(n);
  for (size_t seed = 0; seed < n; ++seed) {
    if (d[seed] <= 0.0F || component[seed] >= 0) continue;
    const int id = static_cast<int>(surfaces.size());
    Surface surface;
    stack.assign(1, static_cast<int>(seed));
    component[seed] = id;
    flood4(
        PixelBox{0, 0, w - 1, h - 1}, w, stack,
        [&](size_t j, size_t i) {
          if (component[j] >= 0 || d[j] <= 0.0F || std::abs(d[j] - d[i]) >= config.continuity_mm) return false;
          component[j] = id;
          return true;
        },
        [&](size_t i) {
          ++surface.pixels;
          surface.depth_sum += d[i];
        });
    surfaces.push_back(surface);
  }
}

FarPlaneCut far_plane_cut(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
                          const std::vector<int>& component, int blob, int w, int h) {
  const auto far = static_cast<float>(config.far_mm);
  const auto reach = static_cast<float>(config.far_mm + config.continuity_mm);
  int boundary = 0;
  int continued = 0;
  float nearest = far;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      if (component[static_cast<size_t>(v) * w + u] != blob) continue;
      nearest = std::min(nearest, unclamped_mm[static_cast<size_t>(v) * w + u]);
      bool edge = false;
      bool beyond = false;
      for (const auto& [du, dv] : {std::pair{-1, 0}, std::pair{1, 0}, std::pair{0, -1}, std::pair{0, 1}}) {
        const int uu = u + du;
        const int vv = v + dv;
        if (uu < 0 || vv < 0 || uu >= w || vv >= h) continue;
        const auto j = static_cast<size_t>(vv) * w + uu;
        if (component[j] == blob) continue;
        edge = true;
        beyond = beyond || (unclamped_mm[j] > far && unclamped_mm[j] <= reach);
      }
      boundary += edge ? 1 : 0;
      continued += beyond ? 1 : 0;
    }
  }
  return {boundary > 0 ? static_cast<double>(continued) / boundary : 0.0, nearest};
}

}  // namespace handtrack
