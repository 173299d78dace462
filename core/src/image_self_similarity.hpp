#pragma once
// E(C_I, C_I) of paper eq. 3, the self-similarity of the image Gaussians that normalises E_sim
// (Sec. 4.1). Private to core: DepthInputBuilder keeps one, so its scratch is reused per frame;
// the public image_self_similarity() (depth_input.hpp) makes a fresh one.
#include "handtrack/core/depth_input.hpp"

#include <cstddef>
#include <vector>

namespace handtrack {

class SelfSimilarity {
 public:
  // Room for `leaves` Gaussians without allocating.
  explicit SelfSimilarity(size_t leaves = 0);
  double operator()(const std::vector<ImageGaussian>& gaussians);

 private:
  std::vector<double> us_, vs_, s2s_;  // the Gaussians sorted by u, as columns
  std::vector<size_t> order_;
};

}  // namespace handtrack
