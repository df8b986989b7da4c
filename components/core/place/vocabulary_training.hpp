// Training a vocabulary tree from the descriptors of many images: hierarchical k-medians (k-means++
// seeding, bitwise-majority medians for binary descriptors), then word weights from the images
// (IDF = log(images / images containing the word)). Deterministic for a seed and any thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "components/core/feature/features.hpp"
#include "components/core/place/vocabulary.hpp"

namespace heslam {

struct VocabularyTrainingOptions {
  int branching = 10;  // k (ORBvoc.txt: 10)
  int levels = 6;      // L (ORBvoc.txt: 6): up to k^L words
  BowWeighting weighting = BowWeighting::kTfIdf;
  BowScoring scoring = BowScoring::kL1;
  std::uint64_t seed = 1;
  int threads = 1;          // subtrees are clustered in parallel; the result does not depend on it
  int max_iterations = 10;  // k-medians iterations per node (stops earlier when stable)
  // The tree is clustered from at most this many descriptors, a uniform sample drawn with `seed`
  // (0 = all). The word weights still count every image's descriptors. Clustering time grows with
  // the sample; ~100 descriptors per word of the final tree are plenty for k = 10, L = 6.
  std::size_t max_cluster_descriptors = 0;
  // Called with one line now and then on long runs (e.g. "level 3/6: 412 nodes"); may be empty.
  std::function<void(const std::string&)> progress;
};

// `images[i]` are the descriptors of training image i (the IDF counts images). Throws
// std::invalid_argument when there are no descriptors or the options are out of range.
//
// Per node: k-means++ seeding (squared Hamming distance, std::mt19937_64 seeded from `seed` and the
// node's path), then assign / bitwise-majority median until no descriptor changes cluster or
// `max_iterations`. A node with <= k descriptors gets one leaf per distinct descriptor (DBoW2), a
// cluster whose descriptors are all equal is a leaf, and nodes at depth L are leaves. Nodes are
// numbered breadth first. Word weight (TF-IDF, IDF): ln(N / n_w) for N images of which n_w reach the
// word, ln(N) for a word no training image reaches; 1 for TF and binary weighting.
Vocabulary train_vocabulary(const std::vector<std::vector<Descriptor>>& images,
                            const VocabularyTrainingOptions& options);

}  // namespace heslam
