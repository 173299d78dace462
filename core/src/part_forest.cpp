#include "handtrack/core/part_forest.hpp"

#include "forest_descent.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string_view>
#include <type_traits>

namespace handtrack {
namespace {

// How much surer the trees must be of a turned reading's labels than of the image's (PartForest::
// label). A rolled hand's turned labels are 20-40 % surer (seed 1, palm / back / head-mounted views
// at 90 / 180 / -90 deg: mean max-class probability 0.48-0.65 -> 0.67-0.85). A hand that swings
// past 45 deg and back (the motion random), whose every roll the trees saw in the image's axes, is
// about as sure either way, and taking the turned labels there cost 0.6 mm on random. 1.0 / 1.1 /
// 1.2 measured with quarter turns on the rolled scenes and the benchmark's seeds 1-3, checked on
// seeds 4-6, and kept for the turns by 45 deg (docs/FOREST.md, "A hand from another image edge").
constexpr double kTurnedReadingMargin = 1.1;

// The pixels of an input's images (row-major, the camera's width) and which of them the forest
// labels: on the hand mask, with a depth.
struct HandPixels {
  const DepthInput& input;
  [[nodiscard]] size_t at(int x, int y) const {
    return static_cast<size_t>(y) * static_cast<size_t>(input.camera.width) + static_cast<size_t>(x);
  }
  [[nodiscard]] bool labelled(int x, int y) const {
    const size_t i = at(x, y);
    return input.hand_mask[i] != 0 && input.filtered_mm[i] > 0.0F;
  }
};

static_assert(std::endian::native == std::endian::little, "the model file is read by memcpy: little-endian only");

constexpr std::array<char, 8> kMagic = {'H', 'T', 'F', 'O', 'R', 'E', 'S', 'T'};
constexpr size_t kFixedHeaderBytes = 36;  // magic .. metadata length, format version 1
constexpr uint32_t kHandAlignedProbes = 1;  // format version 2's probe frame
constexpr size_t kChecksumBytes = 8;
constexpr size_t kNodeBytes = 16;
constexpr size_t kLeafBytes = 2 * kPartForestClasses;
// A node in the file: u[0], u[1], v[0], v[1] (int16), threshold (float32), child (uint32); a leaf:
// kPartForestClasses uint16 counts. In memory they are the same bytes.
static_assert(sizeof(PartForestNode) == kNodeBytes && offsetof(PartForestNode, v) == 4 &&
              offsetof(PartForestNode, threshold) == 8 && offsetof(PartForestNode, child) == 12);
static_assert(sizeof(PartForestLeaf) == kLeafBytes);

// FNV-1a 64 (Fowler, Noll, Vo): offset basis and prime of the 64-bit variant.
constexpr uint64_t kFnvOffsetBasis = 0xcbf29ce484222325ULL;
constexpr uint64_t kFnvPrime = 0x100000001b3ULL;

uint64_t fnv1a64(std::span<const uint8_t> bytes) {
  uint64_t h = kFnvOffsetBasis;
  for (const uint8_t b : bytes) {
    h ^= b;
    h *= kFnvPrime;
  }
  return h;
}

// Bounds-checked little-endian reads; a short read throws "truncated".
class Reader {
 public:
  explicit Reader(std::span<const uint8_t> bytes) : bytes_(bytes) {}

  template <typename T>
  T read(std::string_view what) {
    T value;
    need(sizeof(T), what);
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  void read_bytes(void* out, size_t n, std::string_view what) {
    need(n, what);
    if (n > 0) std::memcpy(out, bytes_.data() + pos_, n);
    pos_ += n;
  }
  void need(size_t n, std::string_view what) const {
    if (n > bytes_.size() - pos_) {
      throw std::runtime_error("truncated: " + std::string(what) + " needs " + std::to_string(n) +
                               " bytes at offset " + std::to_string(pos_) + ", the file has " +
                               std::to_string(bytes_.size()));
    }
  }
  [[nodiscard]] size_t pos() const { return pos_; }

 private:
  std::span<const uint8_t> bytes_;
  size_t pos_ = 0;
};

// Little-endian writes into a buffer sized up front (GCC 12 warns spuriously about a growing one).
class Writer {
 public:
  explicit Writer(size_t size) : bytes_(size) {}
  template <typename T>
  void put(const T& value) {
    put_bytes(&value, sizeof(T));
  }
  void put_bytes(const void* p, size_t n) {
    if (n == 0) return;
    if (n > bytes_.size() - pos_) throw std::logic_error("part forest: serialised size miscounted");
    std::memcpy(bytes_.data() + pos_, p, n);
    pos_ += n;
  }
  [[nodiscard]] size_t pos() const { return pos_; }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
  size_t pos_ = 0;
};

// Levels of a block in lay_out_in_blocks(): the 2 + 4 + 8 nodes below a node, 224 bytes.
constexpr int kBlockLevels = 3;

// Reorders a valid tree's nodes (the same tree: each node's children stay a pair, after it) so
// that a descent, which reads one node per level, touches few cache lines: the nodes of the
// kBlockLevels levels below a node lie together, breadth first, and the blocks follow each other
// breadth first from the root (the top of the tree, which every descent reads, is one contiguous
// run). Numbered breadth first over the whole tree, as the trainer numbers them, every level of a
// descent lies in another part of the forest's 14 MB of nodes. The order depends on the tree's
// shape only, so a tree laid out so is laid out again unchanged. The labels are the same; the
// time goes mostly on frames that meet the forest cold (docs/BENCHMARKS.md, "The forest's nodes in
// blocks": late_fusion_2p_10it, the first configuration of a handtrack-bench run, 483-502 ->
// 553-557 fps, its p99 8.2-8.6 -> 4.1-4.4 ms; warm, preprocessing 0.86 -> 0.82 ms).
void lay_out_in_blocks(PartForestTree& tree) {
  const std::vector<PartForestNode>& nodes = tree.nodes;
  std::vector<PartForestNode> out;
  out.reserve(nodes.size());
  std::vector<uint32_t> placed_at(nodes.size(), 0);  // old index -> new index
  out.push_back(nodes[0]);
  std::vector<uint32_t> block_tops{0};  // old indices, in the order their blocks are laid out
  std::vector<uint32_t> level;
  std::vector<uint32_t> next;
  for (size_t b = 0; b < block_tops.size(); ++b) {
    level.assign(1, block_tops[b]);
    for (int d = 0; d < kBlockLevels; ++d) {
      next.clear();
      for (const uint32_t i : level) {
        if (nodes[i].is_leaf()) continue;
        const uint32_t c = nodes[i].child;
        out[placed_at[i]].child = static_cast<uint32_t>(out.size());
        for (const uint32_t k : {c, c + 1}) {
          placed_at[k] = static_cast<uint32_t>(out.size());
          out.push_back(nodes[k]);
          next.push_back(k);
        }
      }
      level.swap(next);
    }
    for (const uint32_t i : level) {
      if (!nodes[i].is_leaf()) block_tops.push_back(i);
    }
  }
  tree.nodes = std::move(out);
}

std::string validate(const std::vector<PartForestTree>& trees, const PartForestInfo& info) {
  if (trees.empty()) return "no trees";
  if (trees.size() > static_cast<size_t>(PartForest::kMaxTrees)) return "too many trees: " + std::to_string(trees.size());
  const auto positive = [](float f) { return std::isfinite(f) && f > 0.0F; };
  if (!positive(info.reference_fx) || !positive(info.reference_fy)) return "bad reference focal length";
  if (!positive(info.background_mm)) return "bad background depth";
  if (info.metadata.size() > PartForest::kMaxMetadataBytes) return "metadata longer than 64 KiB";
  for (size_t t = 0; t < trees.size(); ++t) {
    const auto& nodes = trees[t].nodes;
    const auto& leaves = trees[t].leaves;
    // The messages are built only for a node that fails: a forest has about a million nodes.
    const auto where = [t] { return "tree " + std::to_string(t); };
    const auto node = [&](size_t i) { return where() + " node " + std::to_string(i); };
    if (nodes.empty()) return where() + ": no nodes";
    if (nodes.size() > PartForest::kMaxNodesPerTree) return where() + ": too many nodes";
    if (leaves.size() > nodes.size()) return where() + ": more leaves than nodes";
    // A tree: every node but the root is the child of exactly one node (two parents would make
    // the paths, which lay_out_in_blocks() follows, grow exponentially with the depth).
    std::vector<uint8_t> parents(nodes.size(), 0);
    for (size_t i = 0; i < nodes.size(); ++i) {
      const PartForestNode& n = nodes[i];
      if (n.is_leaf()) {
        if (n.leaf_index() >= leaves.size()) {
          return node(i) + ": leaf index " + std::to_string(n.leaf_index()) + " out of range (" +
                 std::to_string(leaves.size()) + " leaves)";
        }
        continue;
      }
      // Children strictly after the parent: every path ends in a leaf within nodes.size() steps.
      if (n.child <= i || n.child >= nodes.size() - 1) {
        return node(i) + ": child index " + std::to_string(n.child) + " out of range (" +
               std::to_string(nodes.size()) + " nodes)";
      }
      if (!std::isfinite(n.threshold)) return node(i) + ": threshold is not finite";
      for (const uint32_t c : {n.child, n.child + 1}) {
        if (++parents[c] > 1) return node(c) + ": a second parent (node " + std::to_string(i) + "): not a tree";
      }
    }
    for (size_t i = 1; i < nodes.size(); ++i) {
      if (parents[i] == 0) return node(i) + ": no parent: not part of the tree";
    }
    for (size_t l = 0; l < leaves.size(); ++l) {
      uint32_t sum = 0;
      for (const uint16_t p : leaves[l]) sum += p;
      if (sum == 0) return where() + " leaf " + std::to_string(l) + ": bad label distribution (all zero)";
    }
  }
  return {};
}

}  // namespace

PartForest::PartForest(std::vector<PartForestTree> trees, PartForestInfo info, PartForestOptions options)
    : trees_(std::move(trees)), info_(std::move(info)) {
  if (auto why = validate(trees_, info_); !why.empty()) throw std::invalid_argument("part forest: " + why);
  for (PartForestTree& tree : trees_) lay_out_in_blocks(tree);
  set_options(options);
}

void PartForest::set_options(const PartForestOptions& options) {
  if (options.stride_px < 1 || options.stride_px > 16) {
    throw std::invalid_argument("part forest: stride must be 1..16, got " + std::to_string(options.stride_px));
  }
  options_ = options;
}

size_t PartForest::node_count() const {
  size_t n = 0;
  for (const auto& t : trees_) n += t.nodes.size();
  return n;
}

int PartForest::max_depth() const {
  int deepest = 0;
  for (const auto& t : trees_) {
    // Children come after their parent, so one forward pass settles every depth.
    std::vector<int> depth(t.nodes.size(), 0);
    for (size_t i = 0; i < t.nodes.size(); ++i) {
      deepest = std::max(deepest, depth[i]);
      if (t.nodes[i].is_leaf()) continue;
      depth[t.nodes[i].child] = depth[i] + 1;
      depth[t.nodes[i].child + 1] = depth[i] + 1;
    }
  }
  return deepest;
}

std::vector<uint8_t> PartForest::to_bytes() const {
  size_t size = kFixedHeaderBytes + (info_.hand_aligned ? 4 : 0) + info_.metadata.size() + 8 * trees_.size() +
                kChecksumBytes;
  for (const auto& t : trees_) size += t.nodes.size() * kNodeBytes + t.leaves.size() * kLeafBytes;
  Writer w(size);
  w.put_bytes(kMagic.data(), kMagic.size());
  w.put(info_.hand_aligned ? kFormatVersion : uint32_t{1});
  w.put(static_cast<uint32_t>(kPartForestClasses));
  w.put(static_cast<uint32_t>(trees_.size()));
  w.put(info_.reference_fx);
  w.put(info_.reference_fy);
  w.put(info_.background_mm);
  if (info_.hand_aligned) w.put(kHandAlignedProbes);
  w.put(static_cast<uint32_t>(info_.metadata.size()));
  w.put_bytes(info_.metadata.data(), info_.metadata.size());
  for (const auto& t : trees_) {
    w.put(static_cast<uint32_t>(t.nodes.size()));
    w.put(static_cast<uint32_t>(t.leaves.size()));
  }
  for (const auto& t : trees_) {
    w.put_bytes(t.nodes.data(), t.nodes.size() * kNodeBytes);
    w.put_bytes(t.leaves.data(), t.leaves.size() * kLeafBytes);
  }
  const uint64_t checksum = fnv1a64(std::span<const uint8_t>(w.bytes().data(), w.pos()));
  w.put(checksum);
  return std::move(w.bytes());
}

void PartForest::save(const std::filesystem::path& path) const {
  const std::vector<uint8_t> bytes = to_bytes();
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error("part forest " + path.string() + ": cannot open for writing");
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  f.close();
  if (!f) throw std::runtime_error("part forest " + path.string() + ": write failed");
}

PartForest PartForest::load(const std::filesystem::path& path, PartForestOptions options) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) throw std::runtime_error("part forest " + path.string() + ": cannot open");
  // One read of the whole file (26 MB for the shipped forest): reading it through
  // istreambuf_iterator, byte by byte, took 0.15 s of handtrackd's start-up here.
  const std::streamoff size = f.tellg();
  if (size < 0) throw std::runtime_error("part forest " + path.string() + ": read error");
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  f.seekg(0);
  if (!f.read(reinterpret_cast<char*>(bytes.data()), size)) {
    throw std::runtime_error("part forest " + path.string() + ": read error");
  }
  return from_bytes(bytes, path.string(), options);
}

PartForest PartForest::from_bytes(std::span<const uint8_t> bytes, const std::string& name, PartForestOptions options) {
  const auto fail = [&](const std::string& why) -> std::runtime_error {
    return std::runtime_error("part forest " + name + ": " + why);
  };
  try {
    Reader r(bytes);
    std::array<char, 8> magic{};
    r.read_bytes(magic.data(), magic.size(), "magic");
    if (magic != kMagic) throw fail("bad magic (not a handtrack part forest file)");
    const auto version = r.read<uint32_t>("format version");
    if (version != 1 && version != kFormatVersion) {
      throw fail("unsupported format version " + std::to_string(version) + " (this build reads 1 and " +
                 std::to_string(kFormatVersion) + ")");
    }
    const auto classes = r.read<uint32_t>("class count");
    if (classes != static_cast<uint32_t>(kPartForestClasses)) {
      throw fail("bad class count " + std::to_string(classes) + " (expected " + std::to_string(kPartForestClasses) + ")");
    }
    const auto tree_count = r.read<uint32_t>("tree count");
    if (tree_count == 0 || tree_count > static_cast<uint32_t>(kMaxTrees)) {
      throw fail("bad tree count " + std::to_string(tree_count));
    }
    PartForestInfo info;
    info.reference_fx = r.read<float>("reference fx");
    info.reference_fy = r.read<float>("reference fy");
    info.background_mm = r.read<float>("background depth");
    if (version == kFormatVersion) {
      const auto frame = r.read<uint32_t>("probe frame");
      if (frame != kHandAlignedProbes) throw fail("bad probe frame " + std::to_string(frame) + " (expected 1)");
      info.hand_aligned = true;
    }
    const auto metadata_bytes = r.read<uint32_t>("metadata length");
    if (metadata_bytes > kMaxMetadataBytes) throw fail("bad metadata length " + std::to_string(metadata_bytes));
    info.metadata.resize(metadata_bytes);
    r.read_bytes(info.metadata.data(), metadata_bytes, "metadata");

    std::vector<PartForestTree> trees(tree_count);
    // Node and leaf counts per tree; storage is allocated only after the file size matched them.
    std::vector<std::array<uint32_t, 2>> counts(tree_count);
    uint64_t payload = 0;  // bytes of nodes and leaves; 64-bit so corrupt counts cannot wrap
    for (uint32_t t = 0; t < tree_count; ++t) {
      const auto nodes = r.read<uint32_t>("node count");
      const auto leaves = r.read<uint32_t>("leaf count");
      if (nodes == 0 || nodes > kMaxNodesPerTree) throw fail("tree " + std::to_string(t) + ": bad node count " + std::to_string(nodes));
      if (leaves > nodes) throw fail("tree " + std::to_string(t) + ": bad leaf count " + std::to_string(leaves));
      payload += uint64_t{nodes} * kNodeBytes + uint64_t{leaves} * kLeafBytes;
      counts[t] = {nodes, leaves};
    }
    const uint64_t expected = uint64_t{r.pos()} + payload + kChecksumBytes;
    if (bytes.size() < expected) {
      throw fail("truncated: the header announces " + std::to_string(expected) + " bytes, the file has " +
                 std::to_string(bytes.size()));
    }
    if (bytes.size() > expected) {
      throw fail("trailing garbage: the header announces " + std::to_string(expected) + " bytes, the file has " +
                 std::to_string(bytes.size()));
    }
    uint64_t stored = 0;
    std::memcpy(&stored, bytes.data() + bytes.size() - kChecksumBytes, kChecksumBytes);
    if (stored != fnv1a64(bytes.first(bytes.size() - kChecksumBytes))) throw fail("checksum mismatch (corrupt file)");

    for (uint32_t t = 0; t < tree_count; ++t) {
      trees[t].nodes.resize(counts[t][0]);
      trees[t].leaves.resize(counts[t][1]);
    }
    // Nodes and leaves are laid out in memory as in the file (the static_asserts above), so each
    // tree's arrays are copied whole.
    for (auto& t : trees) {
      r.read_bytes(t.nodes.data(), t.nodes.size() * kNodeBytes, "nodes");
      r.read_bytes(t.leaves.data(), t.leaves.size() * kLeafBytes, "leaves");
    }
    if (auto why = validate(trees, info); !why.empty()) throw fail(why);
    return PartForest(std::move(trees), std::move(info), options);
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.rfind("part forest ", 0) == 0) throw;
    throw fail(what);
  } catch (const std::bad_alloc&) {
    throw fail("out of memory");
  }
}

uint64_t PartForest::classify_batch(const Crop& crop, const Site* sites, int count, uint8_t* out) const {
  const float* depth = crop.depth_mm;
  const size_t stride = static_cast<size_t>(crop.width) + 2;
  // d_I(p): the crop holds the hand's depth, the background constant everywhere else and in a
  // one-pixel border around it, so a probe clamped to the border reads the background wherever it
  // leaves the box: no branch (whether a probe lands on the hand is unpredictable).
  const auto probe = [&](int px, int py) -> float {
    const auto cx = static_cast<size_t>(std::clamp(px, -1, crop.width) + 1);
    const auto cy = static_cast<size_t>(std::clamp(py, -1, crop.height) + 1);
    return depth[cy * stride + cx];
  };
  const double sx = crop.focal_ratio_x;
  const double sy = crop.focal_ratio_y;
  std::array<ProbeSteps, kBatch> steps{};
  for (int p = 0; p < count; ++p) {
    const float d = probe(sites[p].x - crop.x0, sites[p].y - crop.y0);
    steps[static_cast<size_t>(p)] = probe_steps(sx, sy, d, crop.turn);
  }
  // One tree's descent of the batch, scalar (without AVX2, or PartForestOptions::simd_descent off;
  // forest_descent.hpp is the vector one): at[p] ends on pixel p's leaf. The pixels descend in
  // lockstep: their node -> probe -> node chains are independent, so the CPU overlaps their memory
  // and multiply latencies (one chain alone is latency bound). Without a turn, or with a half turn,
  // the steps' cross terms xy and yx are 0 (probe_steps): `unturned` drops their multiplies, the
  // same sums (16 % of the scalar descent on 2026-12-03's host).
  const auto descend = [&](const PartForestTree& tree, std::array<uint32_t, kBatch>& at, auto unturned) {
    const PartForestNode* nodes = tree.nodes.data();
    const auto coordinate = [](int c, int16_t a, int16_t b, int32_t ka, int32_t kb) {
      if constexpr (decltype(unturned)::value) return probe_coordinate(c, a, 0, ka, 0);
      return probe_coordinate(c, a, b, ka, kb);
    };
    for (bool active = true; active;) {
      active = false;
      for (int p = 0; p < count; ++p) {
        const auto q = static_cast<size_t>(p);
        const PartForestNode& n = nodes[at[q]];
        if (n.is_leaf()) {
          // The leaf is read after the descent: fetch it now (a cache miss, like the deep nodes; a
          // leaf's 26 bytes may straddle two cache lines). Later levels find it cached.
          const auto* leaf = reinterpret_cast<const char*>(tree.leaves.data() + n.leaf_index());
          __builtin_prefetch(leaf);
          __builtin_prefetch(leaf + sizeof(PartForestLeaf) - 1);
          continue;
        }
        active = true;
        // Crop coordinates: x + round(offset k) shifts with the crop.
        const int x = sites[p].x - crop.x0;
        const int y = sites[p].y - crop.y0;
        const ProbeSteps& k = steps[q];
        const float a = probe(coordinate(x, n.u[0], n.u[1], k.xx, k.xy), coordinate(y, n.u[1], n.u[0], k.yy, k.yx));
        const float b = probe(coordinate(x, n.v[0], n.v[1], k.xx, k.xy), coordinate(y, n.v[1], n.v[0], k.yy, k.yx));
        at[q] = n.child + ((a - b) < n.threshold ? 0U : 1U);
        // The next node of this pixel is needed only after the other pixels' steps: fetch it now
        // (deep nodes are cache misses, the descent's main cost).
        __builtin_prefetch(nodes + at[q]);
      }
    }
  };
  const bool unturned = crop.turn.sin == 0.0;
  static_assert(kBatch == kDescentLanes);
  // The vector descent where this CPU has it and the batch's steps fit its lanes: decided once for
  // all the trees.
  DescentLanes lanes;
  bool vectorised = options_.simd_descent && avx2_descent_supported();
  if (vectorised) {
    lanes.count = count;
    for (int p = 0; p < (count + 7) / 8 * 8; ++p) {
      const auto q = static_cast<size_t>(std::min(p, count - 1));
      const auto l = static_cast<size_t>(p);
      lanes.x[l] = sites[q].x - crop.x0;
      lanes.y[l] = sites[q].y - crop.y0;
      lanes.xx[l] = steps[q].xx;
      lanes.xy[l] = steps[q].xy;
      lanes.yx[l] = steps[q].yx;
      lanes.yy[l] = steps[q].yy;
    }
    vectorised = lanes_fit_avx2(lanes);
  }
  const DescentCrop descent_crop{depth, crop.width, crop.height};
  std::array<std::array<uint32_t, kPartForestClasses>, kBatch> sum{};
  for (const PartForestTree& tree : trees_) {
    const PartForestNode* nodes = tree.nodes.data();
    alignas(32) std::array<uint32_t, kBatch> at{};
    if (vectorised) {
      descend_avx2(tree, descent_crop, lanes, at.data());
    } else if (unturned) {
      descend(tree, at, std::true_type{});
    } else {
      descend(tree, at, std::false_type{});
    }
    for (int p = 0; p < count; ++p) {
      const auto q = static_cast<size_t>(p);
      const PartForestLeaf& leaf = tree.leaves[nodes[at[q]].leaf_index()];
      for (size_t c = 0; c < leaf.size(); ++c) sum[q][c] += leaf[c];
    }
  }
  uint64_t sure = 0;
  for (int p = 0; p < count; ++p) {
    const auto& s = sum[static_cast<size_t>(p)];
    const auto best = std::max_element(s.begin(), s.end());
    out[p] = static_cast<uint8_t>(best - s.begin());
    sure += *best;
  }
  return sure;
}

void PartForest::label(const DepthInput& input, std::vector<uint8_t>& labels) const {
  const int w = input.camera.width;
  const int h = input.camera.height;
  const size_t n = static_cast<size_t>(std::max(0, w)) * static_cast<size_t>(std::max(0, h));
  labels.assign(n, 0);
  if (n == 0 || input.hand_mask.size() != n || input.filtered_mm.size() != n) return;
  const auto* mask = input.hand_mask.data();
  const HandPixels pixels{input};

  // The hand's bounding box, copied with the background constant off the mask and in a border
  // around it: a probe then needs a clamp, no branch, and the crop is small enough to stay in
  // cache. Storage is per thread and reused, with room for the whole image from a thread's first
  // frame: a hand's box larger than any before must not allocate (the daemon's steady state). So
  // too the labels of a turned reading.
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = mask + pixels.at(0, y);
    uint8_t any = 0;
    for (int x = 0; x < w; ++x) any |= row[x];  // most rows have no hand: one vectorised pass
    if (any == 0) continue;
    // The row's first and last labelled pixels, each found from its end of the row, over the
    // empty mask eight bytes at a time: a scan that stops at the hand.
    const auto empty8 = [&](int x) {
      uint64_t bytes = 0;
      std::memcpy(&bytes, row + x, sizeof(bytes));
      return bytes == 0;
    };
    int first = 0;
    while (first < w && !pixels.labelled(first, y)) {
      ++first;
      while (first + 8 <= w && empty8(first)) first += 8;
    }
    if (first == w) continue;
    int last = w - 1;
    while (!pixels.labelled(last, y)) {
      --last;
      while (last >= 8 && empty8(last - 7)) last -= 8;
    }
    x0 = std::min(x0, first);
    x1 = std::max(x1, last);
    y0 = std::min(y0, y);
    y1 = y;
  }
  thread_local std::vector<float> crop_storage;
  thread_local std::vector<uint8_t> turned_labels;
  const size_t bordered = (static_cast<size_t>(w) + 2) * (static_cast<size_t>(h) + 2);
  if (crop_storage.capacity() < bordered) crop_storage.reserve(bordered);
  if (turned_labels.capacity() < n) turned_labels.reserve(n);
  if (x1 < 0) return;
  Crop crop;
  crop.x0 = x0;
  crop.y0 = y0;
  crop.width = x1 - x0 + 1;
  crop.height = y1 - y0 + 1;
  crop.focal_ratio_x = input.camera.fx / info_.reference_fx;
  crop.focal_ratio_y = input.camera.fy / info_.reference_fy;
  if (info_.hand_aligned) crop.turn = hand_turn(input.unhinted_axis);
  const float background = info_.background_mm;
  const size_t stride = static_cast<size_t>(crop.width) + 2;
  crop_storage.assign(stride * (static_cast<size_t>(crop.height) + 2), background);
  for (int y = y0; y <= y1; ++y) {
    float* row = crop_storage.data() + static_cast<size_t>(y - y0 + 1) * stride + 1;
    const uint8_t* on = mask + pixels.at(x0, y);
    const float* depth = input.filtered_mm.data() + pixels.at(x0, y);
    // HandPixels::labelled without its branch (& for &&), so that the loop is vectorised.
    for (int i = 0; i < crop.width; ++i) row[i] = ((on[i] != 0) & (depth[i] > 0.0F)) ? depth[i] : background;
  }
  crop.depth_mm = crop_storage.data();
  const uint64_t sure = label_hand(input, crop, labels);
  if (info_.hand_aligned || !options_.turned_readings) return;

  // A hand from another image edge: the same sites with the probes turned by the axis' nearest
  // multiple of 45 deg. The turned labelling wins where the trees are surer of it by
  // kTurnedReadingMargin, summed over the same sites. Hands within 22.5 deg of up are labelled once.
  crop.turn = eighth_turn(input.finger_axis);
  if (crop.turn.cos == 1.0) return;
  turned_labels.assign(n, 0);
  if (static_cast<double>(label_hand(input, crop, turned_labels)) > kTurnedReadingMargin * static_cast<double>(sure)) {
    std::copy(turned_labels.begin(), turned_labels.end(), labels.begin());
  }
}

uint64_t PartForest::label_hand(const DepthInput& input, const Crop& crop, std::vector<uint8_t>& labels) const {
  const int w = input.camera.width;
  const int h = input.camera.height;
  const HandPixels pixels{input};
  const int stride = options_.stride_px * std::max(1, w / 320);
  const int x0 = crop.x0;
  const int y0 = crop.y0;
  const int x1 = crop.x0 + crop.width - 1;
  const int y1 = crop.y0 + crop.height - 1;

  // Sites are classified in batches; each then labels its stride x stride block's hand pixels.
  std::array<Site, kBatch> sites{};
  std::array<uint8_t, kBatch> classes{};
  int pending = 0;
  uint64_t sure = 0;
  const auto flush = [&]() {
    sure += classify_batch(crop, sites.data(), pending, classes.data());
    for (int p = 0; p < pending; ++p) {
      const Site& s = sites[static_cast<size_t>(p)];
      const uint8_t l = classes[static_cast<size_t>(p)];
      if (stride == 1) {
        labels[pixels.at(s.x, s.y)] = l;
        continue;
      }
      for (int y = s.block_y; y < std::min(h, s.block_y + stride); ++y) {
        for (int x = s.block_x; x < std::min(w, s.block_x + stride); ++x) {
          if (pixels.labelled(x, y)) labels[pixels.at(x, y)] = l;
        }
      }
    }
    pending = 0;
  };
  const auto add = [&](int x, int y, int bx, int by) {
    sites[static_cast<size_t>(pending++)] = Site{x, y, bx, by};
    if (pending == kBatch) flush();
  };
  if (stride == 1) {
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        if (pixels.labelled(x, y)) add(x, y, x, y);
      }
    }
  } else {
    // One site per block of the image's stride grid that meets the hand's bounding box: its centre
    // when that is on the hand, else its first hand pixel.
    for (int by = y0 - y0 % stride; by <= y1; by += stride) {
      const int ye = std::min(h, by + stride);
      for (int bx = x0 - x0 % stride; bx <= x1; bx += stride) {
        const int xe = std::min(w, bx + stride);
        int sx = std::min(bx + stride / 2, xe - 1);
        int sy = std::min(by + stride / 2, ye - 1);
        if (!pixels.labelled(sx, sy)) {
          sx = -1;
          for (int y = by; y < ye && sx < 0; ++y) {
            for (int x = bx; x < xe; ++x) {
              if (pixels.labelled(x, y)) {
                sx = x;
                sy = y;
                break;
              }
            }
          }
          if (sx < 0) continue;
        }
        add(sx, sy, bx, by);
      }
    }
  }
  if (pending > 0) flush();
  return sure;
}

InPlaneTurn hand_turn(const Eigen::Vector3d& finger_axis) {
  // R (0, -1) = (sin, -cos) must be the axis' image direction (x, y) / |(x, y)|.
  const double norm = std::hypot(finger_axis.x(), finger_axis.y());
  if (!(norm > 1e-9)) return {};
  return {-finger_axis.y() / norm, finger_axis.x() / norm};
}

InPlaneTurn eighth_turn(const Eigen::Vector3d& finger_axis) {
  const InPlaneTurn t = hand_turn(finger_axis);
  constexpr double kHalf = 0.70710678118654752;  // cos 45 deg
  static constexpr std::array<InPlaneTurn, 8> kEighths = {
      {{1.0, 0.0}, {kHalf, kHalf}, {0.0, 1.0}, {-kHalf, kHalf}, {-1.0, 0.0}, {-kHalf, -kHalf}, {0.0, -1.0}, {kHalf, -kHalf}}};
  const long k = std::lround(std::atan2(t.sin, t.cos) / (std::numbers::pi / 4.0));  // -4..4
  return kEighths[static_cast<size_t>((k + 8) % 8)];
}

std::optional<std::filesystem::path> shipped_forest_path() {
  if (const char* env = std::getenv("HANDTRACK_FOREST"); env != nullptr && *env != '\0') return env;
  for (const char* candidate : {HANDTRACK_SOURCE_FOREST, HANDTRACK_INSTALLED_FOREST}) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec)) return candidate;
  }
  return std::nullopt;
}

}  // namespace handtrack
