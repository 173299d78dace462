#include "image_self_similarity.hpp"

#include "fast_exp.hpp"
#include "target_clones.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace handtrack {

namespace {

// Pairs of image Gaussians with |mu_p - mu_q|^2 / 2S > kPairCutoff add less than e^-kPairCutoff of
// their peak to E(C_I,C_I) and count 0.
constexpr double kPairCutoff = 25.0;

// sum_k s2 s2_k / S_k exp(-((u_k - u)^2 + (v_k - v)^2) / 2 S_k), S_k = s2 + s2_k, over the pairs in
// reach: one run of E(C_I,C_I). The hand's leaves lie close together (a third of all pairs are in
// reach, in no predictable order), so the run is branch-free and vectorised like E_sim's pair sums
// (energy.cpp): 2 doubles per SSE2 register, 4 with FMA in the x86-64-v3 clone.
HANDTRACK_TARGET_CLONES double pair_run(const double* us, const double* vs,
                                                                            const double* s2s, size_t n, double u,
                                                                            double v, double s2) {
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (size_t k = 0; k < n; ++k) {
    const double du = us[k] - u;
    const double dv = vs[k] - v;
    const double s = s2 + s2s[k];
    const double x = (du * du + dv * dv) / (2.0 * s);
    const double term = s2 * s2s[k] / s * detail::exp_nonpositive(-x);
    sum += x <= kPairCutoff ? term : 0.0;
  }
  return sum;
}

}  // namespace

SelfSimilarity::SelfSimilarity(size_t leaves) {
  for (auto* column : {&us_, &vs_, &s2s_}) column->reserve(leaves);
  order_.reserve(leaves);
}

double SelfSimilarity::operator()(const std::vector<ImageGaussian>& gaussians) {
  // E(C_I,C_I) = sum_p sum_q D_pq, D_pq = 2 pi s_p^2 s_q^2 / S exp(-|mu_p - mu_q|^2 / 2S),
  // S = s_p^2 + s_q^2 (eq. 3, unit weights): D_pp = pi s_p^2 and D_pq = D_qp, so each unordered pair
  // is summed once and counted twice. Sorted by u, the partners q > p of p that can be in reach lie
  // in one run |u_q - u_p| <= sqrt(2 S_max kPairCutoff).
  auto& us = us_;
  auto& vs = vs_;
  auto& s2s = s2s_;
  auto& order = order_;
  order.resize(gaussians.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return gaussians[a].u < gaussians[b].u; });
  us.clear();
  vs.clear();
  s2s.clear();
  double s2_max = 0.0;
  for (const size_t i : order) {
    us.push_back(gaussians[i].u);
    vs.push_back(gaussians[i].v);
    s2s.push_back(gaussians[i].sigma_px * gaussians[i].sigma_px);
    s2_max = std::max(s2_max, s2s.back());
  }
  double diagonal = 0.0;
  double pairs = 0.0;
  for (size_t p = 0; p < us.size(); ++p) {
    diagonal += std::numbers::pi * s2s[p];
    const double reach = std::sqrt(2.0 * kPairCutoff * (s2s[p] + s2_max));
    const auto first = us.begin() + static_cast<std::ptrdiff_t>(p) + 1;
    const auto n = static_cast<size_t>(std::upper_bound(first, us.end(), us[p] + reach) - first);
    pairs += pair_run(us.data() + p + 1, vs.data() + p + 1, s2s.data() + p + 1, n, us[p], vs[p], s2s[p]);
  }
  return diagonal + 2.0 * 2.0 * std::numbers::pi * pairs;
}

double image_self_similarity(const std::vector<ImageGaussian>& gaussians) { return SelfSimilarity()(gaussians); }

}  // namespace handtrack
