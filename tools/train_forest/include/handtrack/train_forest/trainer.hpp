#pragma once
// Training of the part forest (Shotton et al. 2011, Sec. 3.4; Criminisi and Shotton 2013):
// each tree grows greedily from the root; a node tries `candidates` random (u, v, threshold)
// triples and keeps the one with the largest information gain
//   G = H(Q) - sum_{s in {l, r}} |Q_s| / |Q| H(Q_s),   H = Shannon entropy of the class histogram,
// until the maximum depth, too few samples or a pure node makes it a leaf holding the normalised
// class histogram of its training pixels.
//
// Parallelism: nodes are tasks on a shared queue (depth first), taken by `threads` workers. Every
// random choice of a node is seeded by (seed, tree, the node's path from the root), and the trees
// are renumbered breadth first at the end, so the model is the same for any thread count.

#include "handtrack/core/part_forest.hpp"
#include "handtrack/train_forest/forest_data.hpp"

#include <cstdint>
#include <functional>
#include <vector>

namespace handtrack::forest {

struct TrainOptions {
  int trees = 3;                // paper: 3
  int max_depth = 20;           // paper: 22
  int pixels_per_image = 500;   // paper: 2000 (sampled per tree from each image's hand mask)
  int candidates = 2000;        // feature/threshold pairs per node; paper: 4000
  int thresholds_per_feature = 20;  // each random (u, v) is tried with this many thresholds
  int min_leaf_samples = 8;     // a split must leave at least this many samples on each side
  int max_node_samples = 20000; // larger nodes choose their split on a random subset of this size
  float max_offset_pxmm = 60.0F * static_cast<float>(SpecCamera::kFx);  // |u|, |v| per axis: 60 mm at the reference focal length
  float unary_fraction = 0.25F; // share of features with v = 0, i.e. f = d(x + u/d) - d(x)
  // Probes in the hand's frame (PartForestInfo::hand_aligned): each image's offsets turned by its
  // LabelledImage::turn, as PartForest::label() turns them by the segmentation's unhinted axis.
  bool hand_aligned = false;
  uint64_t seed = 1;
  int threads = 2;
};

struct TrainProgress {
  int tree = 0;
  uint64_t samples_done = 0;   // samples that have reached a leaf in this tree
  uint64_t samples_total = 0;
};

// Trains on the images (the reference camera is `reference`); `metadata` goes into the model.
// `progress` is called from worker threads (serialised), at most a few times a second.
PartForest train_forest(const std::vector<LabelledImage>& images, const CameraIntrinsics& reference,
                        const TrainOptions& options, const std::string& metadata,
                        const std::function<void(const TrainProgress&)>& progress = nullptr);

}  // namespace handtrack::forest
