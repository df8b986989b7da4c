// Training on synthetic clustered descriptors: the clusters are recovered as words, the result is
// deterministic for a seed and independent of the thread count.
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/place/vocabulary_training.hpp"
#include "vocabulary_test_support.hpp"

namespace heslam {
namespace {

// Images of a few descriptors from each cluster, so IDF has something to count.
std::vector<std::vector<Descriptor>> as_images(const std::vector<std::vector<Descriptor>>& clusters, int images) {
  std::vector<std::vector<Descriptor>> out(images);
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    for (std::size_t i = 0; i < clusters[c].size(); ++i) out[(c + i) % images].push_back(clusters[c][i]);
  }
  return out;
}

TEST(VocabularyTraining, RecoversClustersAsWords) {
  const auto clusters = test::clustered_descriptors(8, 60, 4, 11);
  VocabularyTrainingOptions options;
  options.branching = 8;
  options.levels = 1;
  const Vocabulary vocabulary = train_vocabulary(as_images(clusters, 12), options);
  ASSERT_EQ(vocabulary.word_count(), 8u);
  std::set<WordId> words;
  for (const auto& cluster : clusters) {
    const WordId word = vocabulary.word_of(cluster.front());
    for (const Descriptor& d : cluster) ASSERT_EQ(vocabulary.word_of(d), word);
    words.insert(word);
  }
  EXPECT_EQ(words.size(), 8u);  // one word per cluster
}

TEST(VocabularyTraining, DeeperTreeKeepsEachClusterUnderOneNode) {
  // 12 clusters into k = 3, L = 3: every cluster's descriptors pass the same level-1 node.
  const auto clusters = test::clustered_descriptors(12, 40, 3, 5);
  VocabularyTrainingOptions options;
  options.branching = 3;
  options.levels = 3;
  const Vocabulary vocabulary = train_vocabulary(as_images(clusters, 10), options);
  EXPECT_GT(vocabulary.word_count(), 12u);
  for (const auto& cluster : clusters) {
    BowVector bow;
    FeatureVector features;
    vocabulary.transform(cluster, bow, &features, 2);  // depth 1
    EXPECT_EQ(features.nodes.size(), 1u);
  }
}

TEST(VocabularyTraining, SmallNodeGetsOneLeafPerDistinctDescriptor) {
  const std::vector<std::vector<Descriptor>> images = {{test::bytes_set(0, 1), test::bytes_set(0, 2)},
                                                       {test::bytes_set(0, 1), test::bytes_set(0, 3)}};
  const Vocabulary vocabulary = train_vocabulary(images, {});
  EXPECT_EQ(vocabulary.word_count(), 3u);
  EXPECT_EQ(vocabulary.node_count(), 4u);
  // IDF = ln(2 images / images with the word): bytes 0-1 is in both images.
  EXPECT_FLOAT_EQ(vocabulary.word_weight(vocabulary.word_of(test::bytes_set(0, 1))), 0.f);
  EXPECT_FLOAT_EQ(vocabulary.word_weight(vocabulary.word_of(test::bytes_set(0, 2))), std::log(2.f));
}

TEST(VocabularyTraining, DeterministicForASeedAndAnyThreadCount) {
  const auto images = as_images(test::clustered_descriptors(40, 50, 12, 3), 20);
  VocabularyTrainingOptions options;
  options.branching = 4;
  options.levels = 4;
  options.seed = 7;
  const Vocabulary one = train_vocabulary(images, options);
  const Vocabulary again = train_vocabulary(images, options);
  test::expect_same_vocabulary(one, again);
  options.threads = 2;
  const Vocabulary two_threads = train_vocabulary(images, options);
  test::expect_same_vocabulary(one, two_threads);
  options.threads = 3;
  options.max_cluster_descriptors = 1000;
  const Vocabulary sampled_three = train_vocabulary(images, options);
  options.threads = 1;
  const Vocabulary sampled_one = train_vocabulary(images, options);
  test::expect_same_vocabulary(sampled_one, sampled_three);
  options.seed = 8;
  const Vocabulary other_seed = train_vocabulary(images, options);
  EXPECT_NE(other_seed.node_records()[0].descriptor, sampled_one.node_records()[0].descriptor);
}

TEST(VocabularyTraining, ReportsProgressAndRejectsBadInput) {
  const auto images = as_images(test::clustered_descriptors(4, 20, 2, 1), 4);
  std::vector<std::string> lines;
  VocabularyTrainingOptions options;
  options.levels = 2;
  options.progress = [&](const std::string& line) { lines.push_back(line); };
  train_vocabulary(images, options);
  EXPECT_GE(lines.size(), 3u);
  EXPECT_THROW(train_vocabulary({{}, {}}, {}), std::invalid_argument);
  options.branching = 1;
  EXPECT_THROW(train_vocabulary(images, options), std::invalid_argument);
}

}  // namespace
}  // namespace heslam
