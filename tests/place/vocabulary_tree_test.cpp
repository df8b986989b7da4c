// Known answers of the vocabulary tree: a hand-built 2 x 2 tree gives the expected words, BoW and
// feature vectors and L1 scores.
#include <vector>

#include <gtest/gtest.h>

#include "vocabulary_test_support.hpp"

namespace heslam {
namespace {

using test::bytes_set;

TEST(VocabularyTree, DescendsToTheNearestLeaf) {
  const Vocabulary vocabulary = test::tiny_vocabulary();
  EXPECT_EQ(vocabulary.word_count(), 4u);
  EXPECT_EQ(vocabulary.node_count(), 7u);
  EXPECT_EQ(vocabulary.word_of(bytes_set(0, 0)), 0u);
  EXPECT_EQ(vocabulary.word_of(bytes_set(0, 3)), 1u);  // 24 bits from a1's 0, 8 from a2's
  EXPECT_EQ(vocabulary.word_of(bytes_set(0, 32)), 2u);
  EXPECT_EQ(vocabulary.word_of(bytes_set(5, 32)), 3u);
  EXPECT_EQ(vocabulary.node_of_word(3), 6u);
  EXPECT_FLOAT_EQ(vocabulary.word_weight(1), 2.f);
}

TEST(VocabularyTree, TransformGivesTfIdfBowAndFeatureVector) {
  const Vocabulary vocabulary = test::tiny_vocabulary();
  const std::vector<Descriptor> image = {bytes_set(0, 0), bytes_set(0, 4), bytes_set(0, 32), bytes_set(0, 0)};
  BowVector bow;
  FeatureVector features;
  vocabulary.transform(image, bow, &features, 1);
  // Word 0 twice (idf 1), word 1 once (idf 2), word 2 once (idf 0.5): 2 : 2 : 0.5, L1-normalised.
  ASSERT_EQ(bow.size(), 3u);
  EXPECT_EQ(bow.entries[0].first, 0u);
  EXPECT_FLOAT_EQ(bow.entries[0].second, 2.f / 4.5f);
  EXPECT_EQ(bow.entries[1].first, 1u);
  EXPECT_FLOAT_EQ(bow.entries[1].second, 2.f / 4.5f);
  EXPECT_EQ(bow.entries[2].first, 2u);
  EXPECT_FLOAT_EQ(bow.entries[2].second, 0.5f / 4.5f);
  // One level up from the leaves: A (node 1) and B (node 2).
  const std::vector<std::pair<NodeId, std::vector<std::uint32_t>>> expected_up1 = {{1, {0, 1, 3}}, {2, {2}}};
  EXPECT_EQ(features.nodes, expected_up1);
  vocabulary.transform(image, bow, &features, 0);
  const std::vector<std::pair<NodeId, std::vector<std::uint32_t>>> expected_leaves = {{3, {0, 3}}, {4, {1}}, {5, {2}}};
  EXPECT_EQ(features.nodes, expected_leaves);
  vocabulary.transform(image, bow, &features, 5);
  const std::vector<std::pair<NodeId, std::vector<std::uint32_t>>> expected_root = {{0, {0, 1, 2, 3}}};
  EXPECT_EQ(features.nodes, expected_root);
}

TEST(VocabularyTree, L1ScoreIsOneForIdenticalZeroForDisjointImages) {
  const Vocabulary vocabulary = test::tiny_vocabulary();
  BowVector a, b, c, d;
  vocabulary.transform(std::vector<Descriptor>{bytes_set(0, 0), bytes_set(0, 4)}, a, nullptr, 0);
  vocabulary.transform(std::vector<Descriptor>{bytes_set(0, 4), bytes_set(0, 0)}, b, nullptr, 0);
  vocabulary.transform(std::vector<Descriptor>{bytes_set(4, 32)}, c, nullptr, 0);
  EXPECT_NEAR(vocabulary.score(a, b), 1.0, 1e-6);  // float weights
  EXPECT_NEAR(vocabulary.score(a, c), 0.0, 1e-6);
  // {w0: 1} against {w0: 2/3, w2: 1/3}: 1 - 0.5 (1/3 + 1/3) = 2/3.
  vocabulary.transform(std::vector<Descriptor>{bytes_set(0, 0)}, c, nullptr, 0);
  vocabulary.transform(std::vector<Descriptor>{bytes_set(0, 0), bytes_set(0, 32)}, d, nullptr, 0);
  EXPECT_NEAR(vocabulary.score(c, d), 2.0 / 3.0, 1e-6);
}

TEST(VocabularyTree, EmptyVocabularyGivesEmptyVectors) {
  const Vocabulary vocabulary;
  BowVector bow;
  FeatureVector features;
  vocabulary.transform(std::vector<Descriptor>{bytes_set(0, 0)}, bow, &features, 0);
  EXPECT_TRUE(bow.empty());
  EXPECT_TRUE(features.empty());
  EXPECT_EQ(vocabulary.word_of(bytes_set(0, 0)), kNoWord);
}

}  // namespace
}  // namespace heslam
