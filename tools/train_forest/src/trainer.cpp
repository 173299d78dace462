#include "handtrack/train_forest/trainer.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace handtrack::forest {
namespace {

constexpr uint64_t kPixelStream = 0x919E15;  // Rng::stream purposes
constexpr uint64_t kNodeStream = 0x40DE;
constexpr float kShortRangeShare = 0.5F;     // half the features probe within a third of the range
constexpr float kShortRangeFactor = 1.0F / 3.0F;
constexpr double kMinGainNats = 1e-6;        // a split must reduce the entropy by more than this

uint64_t mix(uint64_t x) {  // splitmix64 finaliser: node keys of the children
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// One training pixel: the image, its position in the crop, the probe steps ((f / f_ref) / d(x),
// turned with the hand for a hand-aligned forest), computed as PartForest::label() does
// (probe_steps), and its class.
struct Sample {
  uint32_t image = 0;
  uint16_t x = 0;
  uint16_t y = 0;
  ProbeSteps steps;
  uint8_t label = 0;
};

struct Feature {
  std::array<int16_t, 2> u{};
  std::array<int16_t, 2> v{};
};

struct BuildNode {
  PartForestNode node;  // u, v, threshold; child filled in at renumbering
  int left = -1;        // build ids; -1 for a leaf
  int right = -1;
  PartForestLeaf distribution{};
};

struct Task {
  size_t begin = 0;
  size_t end = 0;
  int depth = 0;
  uint64_t key = 1;
  int id = 0;
};

class TreeBuilder {
 public:
  TreeBuilder(const std::vector<LabelledImage>& images, const TrainOptions& options, int tree,
              const std::function<void(uint64_t)>& leaf_samples)
      : images_(images), o_(options), tree_(tree), leaf_samples_(leaf_samples) {
    xlogx_.resize(static_cast<size_t>(std::max(o_.max_node_samples, 1)) + 1);
    for (size_t c = 1; c < xlogx_.size(); ++c) xlogx_[c] = static_cast<double>(c) * std::log(static_cast<double>(c));
  }

  // Fills samples_ with up to pixels_per_image hand pixels of every image (this tree's draw).
  void sample_pixels(const CameraIntrinsics& reference, const PartForestInfo& info) {
    const double sx = reference.fx / info.reference_fx;
    const double sy = reference.fy / info.reference_fy;
    std::vector<uint32_t> hand;
    for (size_t i = 0; i < images_.size(); ++i) {
      const LabelledImage& im = images_[i];
      hand.clear();
      for (size_t p = 0; p < im.labels.size(); ++p) {
        if (im.labels[p] != LabelledImage::kOffMask) hand.push_back(static_cast<uint32_t>(p));
      }
      synth::Rng rng = synth::Rng::stream(o_.seed ^ kPixelStream, static_cast<uint64_t>(tree_), i);
      const size_t take = std::min(hand.size(), static_cast<size_t>(o_.pixels_per_image));
      for (size_t k = 0; k < take; ++k) {  // partial Fisher-Yates: `take` distinct pixels
        std::swap(hand[k], hand[k + rng.next() % (hand.size() - k)]);
      }
      std::sort(hand.begin(), hand.begin() + static_cast<std::ptrdiff_t>(take));  // memory order
      for (size_t k = 0; k < take; ++k) {
        Sample s;
        s.image = static_cast<uint32_t>(i);
        s.x = static_cast<uint16_t>(hand[k] % static_cast<uint32_t>(im.width));
        s.y = static_cast<uint16_t>(hand[k] / static_cast<uint32_t>(im.width));
        s.steps = probe_steps(sx, sy, im.depth_mm[hand[k]], o_.hand_aligned ? im.turn : InPlaneTurn{});
        s.label = im.labels[hand[k]];
        samples_.push_back(s);
      }
    }
  }

  [[nodiscard]] size_t sample_count() const { return samples_.size(); }

  PartForestTree build() {
    nodes_.assign(1, BuildNode{});
    tasks_.push_back(Task{0, samples_.size(), 0, 1, 0});
    outstanding_ = 1;
    std::vector<std::thread> pool;
    for (int t = 0; t < std::max(1, o_.threads); ++t) pool.emplace_back([this] { work(); });
    for (auto& t : pool) t.join();
    if (error_) std::rethrow_exception(error_);
    return renumber();
  }

 private:
  // d_I(p) of a crop: the background constant outside it (the crop holds the whole hand mask).
  [[nodiscard]] float response(const Sample& s, const Feature& f) const {
    const LabelledImage& im = images_[s.image];
    const auto probe = [&](int px, int py) -> float {
      if (static_cast<unsigned>(px) >= static_cast<unsigned>(im.width) ||
          static_cast<unsigned>(py) >= static_cast<unsigned>(im.height)) {
        return kBackgroundDepthMm;
      }
      return im.depth_mm[static_cast<size_t>(py) * static_cast<size_t>(im.width) + static_cast<size_t>(px)];
    };
    const ProbeSteps& k = s.steps;
    return probe(probe_coordinate(s.x, f.u[0], f.u[1], k.xx, k.xy), probe_coordinate(s.y, f.u[0], f.u[1], k.yx, k.yy)) -
           probe(probe_coordinate(s.x, f.v[0], f.v[1], k.xx, k.xy), probe_coordinate(s.y, f.v[0], f.v[1], k.yx, k.yy));
  }

  Feature random_feature(synth::Rng& rng) const {
    const float range = o_.max_offset_pxmm * (rng.uniform() < kShortRangeShare ? kShortRangeFactor : 1.0F);
    const auto offset = [&]() { return static_cast<int16_t>(std::lround(rng.uniform(-range, range))); };
    Feature f;
    f.u = {offset(), offset()};
    if (rng.uniform() >= o_.unary_fraction) f.v = {offset(), offset()};
    return f;
  }

  // Sum over classes of c log c, and n log n - that sum = n H (nats).
  [[nodiscard]] double n_entropy(const uint32_t* counts, int classes, uint32_t n) const {
    double s = 0.0;
    for (int c = 0; c < classes; ++c) s += xlogx_[counts[c]];
    return xlogx_[n] - s;
  }

  void work() {
    Scratch scratch;
    for (;;) {
      Task task;
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return !tasks_.empty() || outstanding_ == 0; });
        if (tasks_.empty()) return;
        task = tasks_.back();
        tasks_.pop_back();
      }
      std::vector<Task> children;
      try {
        process(task, scratch, children);
      } catch (...) {
        std::lock_guard lock(mutex_);
        if (!error_) error_ = std::current_exception();
      }
      {
        std::lock_guard lock(mutex_);
        // Right first: the stack takes the left child next (depth first, bounded queue).
        for (auto it = children.rbegin(); it != children.rend(); ++it) tasks_.push_back(*it);
        outstanding_ += children.size();
        --outstanding_;
      }
      cv_.notify_all();
    }
  }

  struct Scratch {
    std::vector<uint32_t> subset;
    std::vector<float> responses;
    std::vector<uint8_t> labels;
    std::vector<float> thresholds;
    std::vector<uint32_t> bins;
    std::vector<Sample> buffer;
  };

  void make_leaf(const Task& task, const std::array<uint32_t, kPartForestClasses>& hist) {
    PartForestLeaf leaf{};
    const double n = static_cast<double>(task.end - task.begin);
    for (size_t c = 0; c < leaf.size(); ++c) {
      leaf[c] = static_cast<uint16_t>(std::lround(65535.0 * static_cast<double>(hist[c]) / n));
    }
    {
      std::lock_guard lock(mutex_);
      nodes_[static_cast<size_t>(task.id)].distribution = leaf;
    }
    leaf_samples_(task.end - task.begin);
  }

  void process(const Task& task, Scratch& s, std::vector<Task>& children) {
    const size_t n = task.end - task.begin;
    std::array<uint32_t, kPartForestClasses> hist{};
    for (size_t i = task.begin; i < task.end; ++i) ++hist[samples_[i].label];
    const int present = static_cast<int>(std::count_if(hist.begin(), hist.end(), [](uint32_t c) { return c > 0; }));
    if (task.depth >= o_.max_depth || n < 2 * static_cast<size_t>(o_.min_leaf_samples) || present <= 1) {
      make_leaf(task, hist);
      return;
    }
    synth::Rng rng = synth::Rng::stream(o_.seed ^ kNodeStream, static_cast<uint64_t>(tree_), task.key);

    // The samples that choose the split: all, or a random subset of large nodes (in memory order).
    s.subset.clear();
    if (n > static_cast<size_t>(o_.max_node_samples)) {
      for (int k = 0; k < o_.max_node_samples; ++k) s.subset.push_back(static_cast<uint32_t>(task.begin + rng.next() % n));
      std::sort(s.subset.begin(), s.subset.end());
    } else {
      for (size_t i = task.begin; i < task.end; ++i) s.subset.push_back(static_cast<uint32_t>(i));
    }
    const auto m = static_cast<uint32_t>(s.subset.size());
    // Classes present here, renumbered 0..C-1 so that deep nodes count few classes.
    std::array<uint8_t, kPartForestClasses> local{};
    int classes = 0;
    for (size_t c = 0; c < hist.size(); ++c) {
      if (hist[c] > 0) local[c] = static_cast<uint8_t>(classes++);
    }
    s.labels.resize(m);
    std::vector<uint32_t> parent(static_cast<size_t>(classes), 0);
    for (uint32_t k = 0; k < m; ++k) {
      s.labels[k] = local[samples_[s.subset[k]].label];
      ++parent[s.labels[k]];
    }
    const double parent_nh = n_entropy(parent.data(), classes, m);
    const auto min_side = static_cast<uint32_t>(std::min<size_t>(
        static_cast<size_t>(o_.min_leaf_samples), std::max<size_t>(1, static_cast<size_t>(o_.min_leaf_samples) * m / n)));

    const int per_feature = std::max(1, o_.thresholds_per_feature);
    const int features = std::max(1, o_.candidates / per_feature);
    double best_gain = kMinGainNats * m;  // in units of n H
    Feature best{};
    float best_threshold = 0.0F;
    bool found = false;
    s.responses.resize(m);
    for (int fi = 0; fi < features; ++fi) {
      const Feature f = random_feature(rng);
      for (uint32_t k = 0; k < m; ++k) s.responses[k] = response(samples_[s.subset[k]], f);
      // Thresholds: responses of random samples (the empirical distribution), distinct, sorted.
      s.thresholds.clear();
      for (int t = 0; t < per_feature; ++t) s.thresholds.push_back(s.responses[rng.next() % m]);
      std::sort(s.thresholds.begin(), s.thresholds.end());
      s.thresholds.erase(std::unique(s.thresholds.begin(), s.thresholds.end()), s.thresholds.end());
      const size_t nt = s.thresholds.size();
      // bins[b][c]: samples of class c with exactly b thresholds <= response; threshold k sends
      // bins 0..k left (response < thresholds[k]).
      s.bins.assign((nt + 1) * static_cast<size_t>(classes), 0);
      for (uint32_t k = 0; k < m; ++k) {
        const auto b = static_cast<size_t>(std::upper_bound(s.thresholds.begin(), s.thresholds.end(), s.responses[k]) -
                                           s.thresholds.begin());
        ++s.bins[b * static_cast<size_t>(classes) + s.labels[k]];
      }
      std::array<uint32_t, kPartForestClasses> left{};
      std::array<uint32_t, kPartForestClasses> right{};
      uint32_t nl = 0;
      for (size_t k = 0; k < nt; ++k) {
        for (int c = 0; c < classes; ++c) {
          const uint32_t add = s.bins[k * static_cast<size_t>(classes) + static_cast<size_t>(c)];
          left[static_cast<size_t>(c)] += add;
          nl += add;
        }
        const uint32_t nr = m - nl;
        if (nl < min_side || nr < min_side) continue;
        for (int c = 0; c < classes; ++c) right[static_cast<size_t>(c)] = parent[static_cast<size_t>(c)] - left[static_cast<size_t>(c)];
        // n G = n H(Q) - n_l H(Q_l) - n_r H(Q_r)
        const double gain = parent_nh - n_entropy(left.data(), classes, nl) - n_entropy(right.data(), classes, nr);
        if (gain > best_gain) {
          best_gain = gain;
          best = f;
          best_threshold = s.thresholds[k];
          found = true;
        }
      }
    }
    if (!found) {
      make_leaf(task, hist);
      return;
    }
    // Partition all the node's samples (stable: they stay in memory order for the children).
    auto first = samples_.begin() + static_cast<std::ptrdiff_t>(task.begin);
    auto last = samples_.begin() + static_cast<std::ptrdiff_t>(task.end);
    s.buffer.clear();
    auto out = first;
    for (auto it = first; it != last; ++it) {
      if (response(*it, best) < best_threshold) {
        *out++ = *it;
      } else {
        s.buffer.push_back(*it);
      }
    }
    std::copy(s.buffer.begin(), s.buffer.end(), out);
    const auto mid = task.begin + static_cast<size_t>(out - first);
    if (mid == task.begin || mid == task.end) {
      make_leaf(task, hist);
      return;
    }
    int left_id = 0;
    {
      std::lock_guard lock(mutex_);
      left_id = static_cast<int>(nodes_.size());
      nodes_.emplace_back();
      nodes_.emplace_back();
      BuildNode& b = nodes_[static_cast<size_t>(task.id)];
      b.node.u = best.u;
      b.node.v = best.v;
      b.node.threshold = best_threshold;
      b.left = left_id;
      b.right = left_id + 1;
    }
    children.push_back(Task{task.begin, mid, task.depth + 1, mix(task.key * 2), left_id});
    children.push_back(Task{mid, task.end, task.depth + 1, mix(task.key * 2 + 1), left_id + 1});
  }

  // Breadth-first order, siblings adjacent: independent of the order the workers finished in.
  PartForestTree renumber() const {
    PartForestTree tree;
    std::vector<int> order = {0};
    for (size_t i = 0; i < order.size(); ++i) {
      const BuildNode& b = nodes_[static_cast<size_t>(order[i])];
      if (b.left >= 0) {
        order.push_back(b.left);
        order.push_back(b.right);
      }
    }
    tree.nodes.resize(order.size());
    size_t next_child = 1;
    for (size_t i = 0; i < order.size(); ++i) {
      const BuildNode& b = nodes_[static_cast<size_t>(order[i])];
      PartForestNode n = b.node;
      if (b.left >= 0) {
        n.child = static_cast<uint32_t>(next_child);
        next_child += 2;
      } else {
        n = PartForestNode{};
        n.child = PartForestNode::kLeafBit | static_cast<uint32_t>(tree.leaves.size());
        tree.leaves.push_back(b.distribution);
      }
      tree.nodes[i] = n;
    }
    return tree;
  }

  const std::vector<LabelledImage>& images_;
  const TrainOptions& o_;
  int tree_;
  std::function<void(uint64_t)> leaf_samples_;
  std::vector<double> xlogx_;
  std::vector<Sample> samples_;

  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Task> tasks_;
  size_t outstanding_ = 0;
  std::vector<BuildNode> nodes_;
  std::exception_ptr error_;
};

}  // namespace

PartForest train_forest(const std::vector<LabelledImage>& images, const CameraIntrinsics& reference,
                        const TrainOptions& options, const std::string& metadata,
                        const std::function<void(const TrainProgress&)>& progress) {
  if (options.trees < 1 || options.trees > PartForest::kMaxTrees) throw std::invalid_argument("--trees must be 1..64");
  if (options.max_depth < 1 || options.max_depth > 40) throw std::invalid_argument("--depth must be 1..40");
  if (options.pixels_per_image < 1) throw std::invalid_argument("--pixels-per-image must be >= 1");
  if (options.candidates < 1) throw std::invalid_argument("--candidates must be >= 1");
  if (options.max_offset_pxmm <= 0.0F || options.max_offset_pxmm > 32767.0F) {
    throw std::invalid_argument("offset range must be within int16");
  }
  PartForestInfo info;
  info.reference_fx = static_cast<float>(reference.fx);
  info.reference_fy = static_cast<float>(reference.fy);
  info.background_mm = kBackgroundDepthMm;
  info.hand_aligned = options.hand_aligned;
  info.metadata = metadata;
  std::vector<PartForestTree> trees;
  std::mutex progress_mutex;
  for (int t = 0; t < options.trees; ++t) {
    TrainProgress state;
    state.tree = t;
    auto last = std::chrono::steady_clock::now();
    const auto on_leaf = [&](uint64_t samples) {
      std::lock_guard lock(progress_mutex);
      state.samples_done += samples;
      const auto now = std::chrono::steady_clock::now();
      if (progress && now - last > std::chrono::milliseconds(250)) {
        last = now;
        progress(state);
      }
    };
    TreeBuilder builder(images, options, t, on_leaf);
    builder.sample_pixels(reference, info);
    state.samples_total = builder.sample_count();
    if (state.samples_total == 0) throw std::invalid_argument("no hand pixels to train on");
    trees.push_back(builder.build());
    if (progress) progress(state);
  }
  return PartForest(std::move(trees), std::move(info));
}

}  // namespace handtrack::forest
