// DescriptorMatcher: known correspondences between noisy copies are recovered; ambiguous and far
// descriptors are rejected by the ratio test and the distance threshold.
#include <random>

#include <gtest/gtest.h>

#include "components/core/match/descriptor_matcher.hpp"

namespace heslam {
namespace {

Descriptor random_descriptor(std::mt19937& rng) {
  Descriptor d;
  for (auto& b : d) b = static_cast<std::uint8_t>(rng() & 0xFF);
  return d;
}

Descriptor flip_bits(Descriptor d, int count, std::mt19937& rng) {
  std::uniform_int_distribution<int> bit(0, 255);
  for (int k = 0; k < count; ++k) {
    const int b = bit(rng);
    d[static_cast<std::size_t>(b / 8)] ^= static_cast<std::uint8_t>(1u << (b % 8));
  }
  return d;
}

TEST(DescriptorMatcher, HammingDistanceKnownAnswer) {
  Descriptor a{};
  Descriptor b{};
  b[0] = 0xFF;
  b[31] = 0x01;
  EXPECT_EQ(hamming_distance(a, b), 9);
  EXPECT_EQ(hamming_distance(b, b), 0);
  EXPECT_EQ(TH_LOW, 50);
  EXPECT_EQ(TH_HIGH, 100);
}

TEST(DescriptorMatcher, RecoversPermutedNoisyCopies) {
  std::mt19937 rng(7);
  const int n = 500;
  std::vector<Descriptor> query(n), train(n);
  std::vector<int> permutation(n);
  for (int i = 0; i < n; ++i) permutation[i] = (i * 37 + 11) % n;  // 37 is coprime with 500
  for (int i = 0; i < n; ++i) {
    query[i] = random_descriptor(rng);
    train[permutation[i]] = flip_bits(query[i], 20, rng);  // <= 20 bits apart, random pairs ~128
  }
  const DescriptorMatcher matcher;
  const auto matches = matcher.match(query, train);
  ASSERT_EQ(matches.size(), static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(matches[i].query, i);
    EXPECT_EQ(matches[i].train, permutation[i]);
    EXPECT_LE(matches[i].distance, 20);
  }
}

TEST(DescriptorMatcher, RatioThresholdAndOneToOne) {
  std::mt19937 rng(3);
  const Descriptor a = random_descriptor(rng);
  // Two nearly equal candidates: ambiguous, rejected by the ratio test.
  std::vector<Descriptor> train = {flip_bits(a, 10, rng), flip_bits(a, 11, rng), random_descriptor(rng)};
  std::vector<Descriptor> query = {a};
  EXPECT_TRUE(DescriptorMatcher().match(query, train).empty());
  // Far descriptor: rejected by max_distance.
  train = {flip_bits(a, 70, rng)};
  EXPECT_TRUE(DescriptorMatcher().match(query, train).empty());
  DescriptorMatcherOptions loose;
  loose.max_distance = TH_HIGH;
  EXPECT_EQ(DescriptorMatcher(loose).match(query, train).size(), 1u);
  // Two queries wanting the same train descriptor: the closer one keeps it.
  train = {a};
  query = {flip_bits(a, 9, rng), flip_bits(a, 3, rng)};
  const auto matches = DescriptorMatcher().match(query, train);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].query, 1);
  // best_two over candidates.
  const std::vector<Descriptor> set = {random_descriptor(rng), a, flip_bits(a, 5, rng)};
  const std::vector<int> candidates = {0, 2};
  const BestTwo best = best_two(a, set, candidates);
  EXPECT_EQ(best.index, 2);
  EXPECT_LE(best.distance, 5);
  EXPECT_GT(best.second_distance, 50);
}

}  // namespace
}  // namespace heslam
