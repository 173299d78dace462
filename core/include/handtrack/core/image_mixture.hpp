#pragma once
// The image mixture C_I laid out for E_sim's pair sums (paper eq. 6): structure-of-arrays columns,
// built once per frame (DepthInputBuilder::build) and read by every energy evaluation.
//
// A model Gaussian p only interacts with the image Gaussians q inside its depth factor's reach:
// Delta(p,q) = 0 for |d_p - d_q| >= reach (eq. 7; Sec. 4.3 for the label factor, which also needs
// l_p = l_q). So the mixture is kept twice: ordered by depth, and grouped by part label with each
// group ordered by depth. The Gaussians a model Gaussian can reach are then one contiguous slice of
// the columns, found by binary search.

#include <cstddef>
#include <vector>

namespace handtrack {

struct ImageGaussian;

// A contiguous run of image Gaussians: means (px), sigma_q^2 (px^2) and depths d_q (mm).
struct ImageMixtureSlice {
  const double* u = nullptr;
  const double* v = nullptr;
  const double* sigma2 = nullptr;
  const double* depth_mm = nullptr;
  std::size_t size = 0;
  std::size_t first = 0;  // the index of its first Gaussian in its ordering (by depth, or by label)
};

class ImageMixture {
 public:
  // Rebuilds the columns from the quadtree's Gaussians (labels >= 0). Storage is reused: no
  // allocation once a frame of this size has been seen.
  void assign(const std::vector<ImageGaussian>& gaussians);
  // Room for n Gaussians, so that assign() of up to n, and copying such a mixture into this one,
  // allocate nothing.
  void reserve(std::size_t n);

  [[nodiscard]] std::size_t size() const { return by_depth_.depth_mm.size(); }
  // The image Gaussians with lo_mm <= d_q <= hi_mm, any label.
  [[nodiscard]] ImageMixtureSlice depth_slice(double lo_mm, double hi_mm) const;
  // The image Gaussians with part label `label` and lo_mm <= d_q <= hi_mm.
  [[nodiscard]] ImageMixtureSlice label_slice(int label, double lo_mm, double hi_mm) const;
  // sigma_q^2 of all size() Gaussians in the order of depth_slice()'s, resp. label_slice()'s,
  // slices: a slice's Gaussian k is Gaussian first + k here.
  [[nodiscard]] const double* sigma2_by_depth() const { return by_depth_.sigma2.data(); }
  [[nodiscard]] const double* sigma2_by_label() const { return by_label_.sigma2.data(); }

  // Scratch of a capped E_sim (SimilarityTerm): two columns of size() values, sized with the
  // Gaussians, so that no evaluation allocates. Each evaluation overwrites them: a mixture is
  // evaluated by one thread at a time (each hand, each search has a DepthInput of its own).
  struct Coverage {
    double* covered = nullptr;
    double* open = nullptr;
  };
  [[nodiscard]] Coverage coverage_scratch() const { return {covered_.data(), open_.data()}; }
  // Scratch of `values` doubles for what a capped E_sim's first pass keeps of each pair for its
  // second (SimilarityTerm). reserve(n) makes room for two values per pair of n image Gaussians
  // with up to kMaxPairedModelGaussians model Gaussians; more grows it (allocates). Its contents
  // are not copied with the mixture.
  [[nodiscard]] double* pair_scratch(std::size_t values) const;
  static constexpr std::size_t kMaxPairedModelGaussians = 64;  // kMaxModelGaussians (kinematics.hpp)

 private:
  struct Columns {
    std::vector<double> u, v, sigma2, depth_mm;
    void resize(std::size_t n);
    void reserve(std::size_t n);
    void set(std::size_t i, const ImageGaussian& g);
    // [begin, end) narrowed to lo_mm <= d_q <= hi_mm (the range is ordered by depth).
    [[nodiscard]] ImageMixtureSlice slice(std::size_t begin, std::size_t end, double lo_mm, double hi_mm) const;
    // Gaussians [first, last) as a slice.
    [[nodiscard]] ImageMixtureSlice span(std::size_t first, std::size_t last) const;
  };
  // Where in by_depth_ a depth lies, so that depth_slice() searches a few Gaussians, not all: the
  // depth range is cut into as many buckets as there are Gaussians, bucket(d) = floor((d - origin)
  // / width) clamped to [0, count - 1]; bucket b's Gaussians are [first[b], first[b + 1]). Since
  // bucket() never decreases with d, every Gaussian before first[bucket(x)] is shallower than x and
  // every one from first[bucket(x) + 1] on is deeper: the bound x's place is within its bucket.
  struct DepthIndex {
    double origin_mm = 0.0;
    double inv_width = 1.0;
    std::vector<std::size_t> first;  // count + 1 entries
    void build(const std::vector<double>& sorted_depth_mm);
    [[nodiscard]] std::size_t bucket(double depth_mm) const;
  };
  Columns by_depth_;
  DepthIndex depth_index_;
  Columns by_label_;
  std::vector<std::size_t> label_begin_;  // label l is by_label_[label_begin_[l], label_begin_[l + 1])
  std::vector<std::size_t> order_;        // scratch for sorting
  mutable std::vector<double> covered_;   // coverage_scratch()
  mutable std::vector<double> open_;
  // pair_scratch(): a copy of the mixture gets none of it (nor its room: reserve() the copy).
  struct Scratch {
    std::vector<double> values;
    Scratch() = default;
    Scratch(const Scratch& /*other*/) {}
    Scratch& operator=(const Scratch& /*other*/) { return *this; }
    Scratch(Scratch&&) noexcept = default;
    Scratch& operator=(Scratch&&) noexcept = default;
    ~Scratch() = default;
  };
  mutable Scratch pairs_;
};

}  // namespace handtrack
