// Shared helpers of the vocabulary tests: a hand-built tiny tree, synthetic clustered descriptors,
// and field-by-field comparison of vocabularies.
#pragma once

#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/place/vocabulary.hpp"

namespace heslam::test {

// Descriptor with bytes [first, last) set to 0xff, the rest 0.
inline Descriptor bytes_set(std::size_t first, std::size_t last) {
  Descriptor d{};
  for (std::size_t i = first; i < last; ++i) d[i] = 0xff;
  return d;
}

// k = 2, L = 2: root -> A (zeros), B (ones); A -> leaves a1 (zeros), a2 (bytes 0-3 set);
// B -> leaves b1 (ones), b2 (bytes 4-31 set). Words 0..3 = a1, a2, b1, b2 with idf 1, 2, 0.5, 1.
inline Vocabulary tiny_vocabulary() {
  const std::vector<Vocabulary::NodeRecord> nodes = {
      {0, false, bytes_set(0, 0), 0.f}, {0, false, bytes_set(0, 32), 0.f}, {1, true, bytes_set(0, 0), 1.f},
      {1, true, bytes_set(0, 4), 2.f},  {2, true, bytes_set(0, 32), 0.5f}, {2, true, bytes_set(4, 32), 1.f},
  };
  return Vocabulary(2, 2, BowScoring::kL1, BowWeighting::kTfIdf, nodes);
}

// `clusters` random centres, `per_cluster` descriptors each with up to `max_flips` random bits flipped.
// Returned grouped by cluster.
inline std::vector<std::vector<Descriptor>> clustered_descriptors(int clusters, int per_cluster, int max_flips,
                                                                  std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<Descriptor>> groups(clusters);
  for (auto& group : groups) {
    Descriptor centre;
    for (auto& byte : centre) byte = static_cast<std::uint8_t>(rng());
    for (int i = 0; i < per_cluster; ++i) {
      Descriptor d = centre;
      const int flips = static_cast<int>(rng() % (max_flips + 1));
      for (int f = 0; f < flips; ++f) {
        const int bit = static_cast<int>(rng() % 256);
        d[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
      }
      group.push_back(d);
    }
  }
  return groups;
}

inline void expect_same_vocabulary(const Vocabulary& a, const Vocabulary& b) {
  EXPECT_EQ(a.branching(), b.branching());
  EXPECT_EQ(a.levels(), b.levels());
  EXPECT_EQ(a.scoring(), b.scoring());
  EXPECT_EQ(a.weighting(), b.weighting());
  ASSERT_EQ(a.node_count(), b.node_count());
  ASSERT_EQ(a.word_count(), b.word_count());
  const auto na = a.node_records();
  const auto nb = b.node_records();
  for (std::size_t i = 0; i < na.size(); ++i) {
    ASSERT_EQ(na[i].parent, nb[i].parent) << "node " << i + 1;
    ASSERT_EQ(na[i].is_leaf, nb[i].is_leaf) << "node " << i + 1;
    ASSERT_EQ(na[i].descriptor, nb[i].descriptor) << "node " << i + 1;
    ASSERT_EQ(na[i].weight, nb[i].weight) << "node " << i + 1;
  }
}

inline void expect_same_transform(const Vocabulary& a, const Vocabulary& b, const std::vector<Descriptor>& descriptors,
                                  int levels_up) {
  BowVector bow_a, bow_b;
  FeatureVector fv_a, fv_b;
  a.transform(descriptors, bow_a, &fv_a, levels_up);
  b.transform(descriptors, bow_b, &fv_b, levels_up);
  EXPECT_EQ(bow_a.entries, bow_b.entries);
  EXPECT_EQ(fv_a.nodes, fv_b.nodes);
}

}  // namespace heslam::test
