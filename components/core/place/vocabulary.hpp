// The ORB vocabulary tree (hierarchical k-medians over 256-bit descriptors, Galvez-Lopez & Tardos
// 2012, as DBoW2 uses it): maps descriptors to words, weights them (TF-IDF), scores two images.
//
// Storage is flat arrays: per node id (root = 0) and per child slot (CSR: the children of a node are
// consecutive slots holding their descriptors and where their own children start), so a 1M-word tree
// loads without per-node allocation and one descent step reads two contiguous blocks. transform()
// descends 16 descriptors at a time and prefetches each one's next blocks, which hides most cache
// misses of a 1M-word tree. Immutable after construction: share one const Vocabulary between threads.
// Files: vocabulary_io.hpp (DBoW2 text, own binary). Training: vocabulary_training.hpp.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "components/core/feature/features.hpp"
#include "components/core/place/bow_vector.hpp"

namespace heslam {

// Numeric values are DBoW2's (the text format stores them).
enum class BowWeighting : int { kTfIdf = 0, kTf = 1, kIdf = 2, kBinary = 3 };
enum class BowScoring : int { kL1 = 0, kL2 = 1, kChiSquare = 2, kKl = 3, kBhattacharyya = 4, kDotProduct = 5 };
const char* to_string(BowWeighting weighting);
const char* to_string(BowScoring scoring);

inline constexpr WordId kNoWord = 0xffffffffu;

class Vocabulary {
 public:
  // One node of the tree, as the files store it: nodes other than the root in any order where a
  // parent precedes its children (DBoW2 writes breadth first). Word ids are given to leaves in
  // node-id order.
  struct NodeRecord {
    NodeId parent = 0;
    bool is_leaf = false;
    Descriptor descriptor{};
    float weight = 0.f;  // idf (TF-IDF, IDF) or 1; meaningful for leaves
  };

  Vocabulary() = default;  // empty: transform() gives empty vectors

  // Builds the tree from its nodes (index i in `nodes` is node id i + 1; the root is implicit).
  // Throws std::invalid_argument naming the node when a parent id is out of range or not earlier,
  // or when branching / levels are not positive.
  Vocabulary(int branching, int levels, BowScoring scoring, BowWeighting weighting, std::span<const NodeRecord> nodes);

  // The same nodes as packed little-endian columns, as heslam's binary file stores them (n nodes:
  // parents n x u32, is_leaf n x u8, descriptors n x 32 bytes, weights n x f32), so a file is turned
  // into a tree without an intermediate copy. Same checks as the constructor.
  struct NodeColumns {
    std::span<const std::uint8_t> parents;
    std::span<const std::uint8_t> is_leaf;
    std::span<const std::uint8_t> descriptors;
    std::span<const std::uint8_t> weights;
  };
  static Vocabulary from_columns(int branching, int levels, BowScoring scoring, BowWeighting weighting,
                                 const NodeColumns& columns);

  int branching() const { return branching_; }
  int levels() const { return levels_; }
  BowScoring scoring() const { return scoring_; }
  BowWeighting weighting() const { return weighting_; }
  bool empty() const { return node_of_word_.empty(); }
  std::size_t node_count() const { return parent_.size(); }  // including the root
  std::size_t word_count() const { return node_of_word_.size(); }

  // The leaf a descriptor descends to (closest child by Hamming distance at every level, first
  // child on ties, as DBoW2); kNoWord for an empty vocabulary.
  WordId word_of(const Descriptor& descriptor) const;
  float word_weight(WordId word) const;
  NodeId node_of_word(WordId word) const { return node_of_word_[word]; }

  // The image's BoW vector (weights per the vocabulary's weighting, L1-normalised) and, when
  // `features` is not null, its feature vector: feature i filed under the node of its path at depth
  // levels() - levels_up (the leaf itself for levels_up = 0; the root for levels_up >= levels()).
  // ORB-SLAM2 matches keyframes with levels_up = 4 on a 6-level tree.
  void transform(std::span<const Descriptor> descriptors, BowVector& bow, FeatureVector* features, int levels_up) const;

  // Similarity of two BoW vectors computed by this vocabulary, DBoW2's definition for the
  // vocabulary's scoring: L1 gives 1 - 0.5 * |a - b|_1 in [0, 1] (1 = identical).
  double score(const BowVector& a, const BowVector& b) const;

  // Read access for the writers and tests: the node records in node-id order (root excluded).
  std::vector<NodeRecord> node_records() const;

 private:
  // One child slot: which node it is, and where that node's children are (or its word, for a leaf).
  struct Slot {
    NodeId node = 0;
    std::uint32_t first_child_or_word = 0;  // slot of its first child, or its word id when child_count == 0
    std::uint32_t child_count = 0;
  };

  Vocabulary(int branching, int levels, BowScoring scoring, BowWeighting weighting);
  // Fills the slots from parent_ and the leaf flags once parent_, weight_ and the per-node
  // descriptors are set; validates the tree. `descriptor_of(id)` gives node id's descriptor.
  // The slot of `node`'s child closest to `descriptor` (first on ties); `node` must have children.
  std::uint32_t closest_child(const Descriptor& descriptor, const Slot& node) const;
  template <typename DescriptorOf>
  void link(std::span<const std::uint8_t> is_leaf, DescriptorOf&& descriptor_of);

  int branching_ = 0;
  int levels_ = 0;
  BowScoring scoring_ = BowScoring::kL1;
  BowWeighting weighting_ = BowWeighting::kTfIdf;
  std::vector<NodeId> parent_;               // per node; root's parent is 0
  std::vector<float> weight_;                // per node
  std::vector<WordId> word_;                 // per node: its word id, or kNoWord for inner nodes
  std::vector<std::uint32_t> slot_of_node_;  // per node: its child slot (root: unused)
  Slot root_;                                // where the root's children are
  std::vector<Slot> slot_;                   // per child slot
  std::vector<Descriptor> slot_descriptor_;  // per child slot
  std::vector<NodeId> node_of_word_;
};

}  // namespace heslam
