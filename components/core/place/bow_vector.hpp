// Bag-of-words representations of one image's ORB descriptors (Galvez-Lopez & Tardos 2012):
// the weighted word histogram used for scoring, and the feature vector (the "direct index") that
// groups feature indices by vocabulary node so two images can be matched word by word.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace heslam {

using WordId = std::uint32_t;  // index of a leaf of the vocabulary tree, 0 .. word_count()-1
using NodeId = std::uint32_t;  // index of any node of the tree, 0 = root

// Sorted by word id, each word once, weights L1-normalised (sum of |w| = 1) when non-empty.
struct BowVector {
  std::vector<std::pair<WordId, float>> entries;

  bool empty() const { return entries.empty(); }
  std::size_t size() const { return entries.size(); }
};

// Sorted by node id; per node the indices of the features (into the descriptor array the vector was
// computed from) whose path through the tree passes that node, ascending.
struct FeatureVector {
  std::vector<std::pair<NodeId, std::vector<std::uint32_t>>> nodes;

  bool empty() const { return nodes.empty(); }
};

}  // namespace heslam
