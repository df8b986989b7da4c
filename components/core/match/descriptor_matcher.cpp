// Brute-force descriptor matching: best two per query, ratio test, one-to-one resolution.
#include "components/core/match/descriptor_matcher.hpp"

#include <algorithm>

namespace heslam {
namespace {

inline void offer(BestTwo& best, int index, int distance) {
  if (distance < best.distance) {
    best.second_distance = best.distance;
    best.distance = distance;
    best.index = index;
  } else if (distance < best.second_distance) {
    best.second_distance = distance;
  }
}

}  // namespace

BestTwo best_two(const Descriptor& query, std::span<const Descriptor> train) {
  BestTwo best;
  for (std::size_t j = 0; j < train.size(); ++j) offer(best, static_cast<int>(j), hamming_distance(query, train[j]));
  return best;
}

BestTwo best_two(const Descriptor& query, std::span<const Descriptor> train, std::span<const int> candidates) {
  BestTwo best;
  for (int j : candidates) offer(best, j, hamming_distance(query, train[static_cast<std::size_t>(j)]));
  return best;
}

std::vector<DescriptorMatch> DescriptorMatcher::match(std::span<const Descriptor> query,
                                                      std::span<const Descriptor> train) const {
  // For each train descriptor, the query currently holding it (the one-to-one constraint).
  std::vector<int> owner(train.size(), -1);
  std::vector<int> owner_distance(train.size(), std::numeric_limits<int>::max());
  for (std::size_t i = 0; i < query.size(); ++i) {
    const BestTwo best = best_two(query[i], train);
    if (best.index < 0 || best.distance > options_.max_distance) continue;
    if (best.second_distance != std::numeric_limits<int>::max() &&
        !(static_cast<float>(best.distance) < options_.ratio * static_cast<float>(best.second_distance))) {
      continue;
    }
    const auto j = static_cast<std::size_t>(best.index);
    if (best.distance < owner_distance[j]) {  // strict: on ties the earlier (smaller) query index keeps it
      owner[j] = static_cast<int>(i);
      owner_distance[j] = best.distance;
    }
  }
  std::vector<DescriptorMatch> matches;
  for (std::size_t j = 0; j < train.size(); ++j) {
    if (owner[j] < 0) continue;
    if (options_.cross_check) {
      const BestTwo back = best_two(train[j], query);
      if (back.index != owner[j]) continue;
    }
    matches.push_back({owner[j], static_cast<int>(j), owner_distance[j]});
  }
  std::sort(matches.begin(), matches.end(),
            [](const DescriptorMatch& a, const DescriptorMatch& b) { return a.query < b.query; });
  return matches;
}

}  // namespace heslam
