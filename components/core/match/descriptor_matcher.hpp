// Brute-force Hamming matching of rBRIEF descriptors with Lowe's ratio test, and the best-two search
// over a candidate list that projection and stereo searches build on.
#pragma once

#include <limits>
#include <span>
#include <vector>

#include "components/core/feature/features.hpp"

namespace heslam {

// ORB-SLAM2's thresholds on 256-bit Hamming distances: TH_LOW for strict matches (bag-of-words,
// triangulation, relocalization), TH_HIGH for projection and stereo searches.
inline constexpr int TH_LOW = 50;
inline constexpr int TH_HIGH = 100;

// The two smallest distances of one descriptor against a set; index -1 when the set is empty.
struct BestTwo {
  int index = -1;
  int distance = std::numeric_limits<int>::max();
  int second_distance = std::numeric_limits<int>::max();
};

// Best two over all of `train`.
BestTwo best_two(const Descriptor& query, std::span<const Descriptor> train);
// Best two over train[candidates[k]] (e.g. FeatureGrid::in_area results); index is into `train`.
BestTwo best_two(const Descriptor& query, std::span<const Descriptor> train, std::span<const int> candidates);

struct DescriptorMatch {
  int query = -1;  // index into the query descriptors
  int train = -1;  // index into the train descriptors
  int distance = 0;
};

struct DescriptorMatcherOptions {
  int max_distance = TH_LOW;  // accept only best distance <= this
  // Accept only best < ratio * second best (ORB-SLAM2 uses 0.6 - 0.9 by context; 0.8 is Lowe's value).
  float ratio = 0.8f;
  // Keep a match only if the query is also the best for its train descriptor.
  bool cross_check = false;
};

class DescriptorMatcher {
 public:
  explicit DescriptorMatcher(const DescriptorMatcherOptions& options = {}) : options_(options) {}

  // One match per query at most and one per train at most (on conflict the smaller distance wins, then
  // the smaller query index); result ordered by query index. Deterministic.
  std::vector<DescriptorMatch> match(std::span<const Descriptor> query, std::span<const Descriptor> train) const;

  const DescriptorMatcherOptions& options() const { return options_; }

 private:
  DescriptorMatcherOptions options_;
};

}  // namespace heslam
