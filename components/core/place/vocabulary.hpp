// The ORB vocabulary tree (hierarchical k-medians over 256-bit descriptors, Galvez-Lopez & Tardos
// 2012, as DBoW2 uses it): maps descriptors to words, weights them (TF-IDF), scores two images.
//
// Storage is flat arrays indexed by node id (root = 0), children in CSR form, so a 1M-word tree
// loads in one block without per-node allocation and a descriptor descends with one Hamming
// distance per child. Immutable after construction: share one const Vocabulary between threads.
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
  Vocabulary(int branching, int levels, BowScoring scoring, BowWeighting weighting,
             std::span<const NodeRecord> nodes);

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
  void transform(std::span<const Descriptor> descriptors, BowVector& bow, FeatureVector* features,
                 int levels_up) const;

  // Similarity of two BoW vectors computed by this vocabulary, DBoW2's definition for the
  // vocabulary's scoring: L1 gives 1 - 0.5 * |a - b|_1 in [0, 1] (1 = identical).
  double score(const BowVector& a, const BowVector& b) const;

  // Read access for the writers and tests: the node records in node-id order (root excluded).
  std::vector<NodeRecord> node_records() const;

 private:
  int branching_ = 0;
  int levels_ = 0;
  BowScoring scoring_ = BowScoring::kL1;
  BowWeighting weighting_ = BowWeighting::kTfIdf;
  std::vector<NodeId> parent_;                // per node; root's parent is 0
  std::vector<Descriptor> descriptor_;        // per node (root's is zero)
  std::vector<float> weight_;                 // per node
  std::vector<WordId> word_;                  // per node: its word id, or kNoWord for inner nodes
  std::vector<std::uint8_t> depth_;           // per node: root 0
  std::vector<std::uint32_t> child_begin_;    // CSR: children of n are child_[child_begin_[n] .. child_begin_[n+1])
  std::vector<NodeId> child_;
  std::vector<NodeId> node_of_word_;
};

}  // namespace heslam
