// DetectLoop: minimum covisible score, database candidates, covisibility consistency.
#include "components/core/loop/bow_loop_detector.hpp"

#include <algorithm>
#include <string>

namespace heslam {
namespace {

// The query's covisible keyframes and the candidate's: ORB-SLAM2 uses all connected keyframes.
std::set<KeyframeId> group_of(const Map& map, KeyframeId id) {
  std::set<KeyframeId> group{id};
  if (const Keyframe* keyframe = map.keyframe(id)) {
    for (const auto& [neighbour, weight] : keyframe->covisible) group.insert(neighbour);
  }
  return group;
}

bool share_a_keyframe(const std::set<KeyframeId>& a, const std::set<KeyframeId>& b) {
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (*ia < *ib) {
      ++ia;
    } else if (*ib < *ia) {
      ++ib;
    } else {
      return true;
    }
  }
  return false;
}

}  // namespace

BowLoopDetector::BowLoopDetector(std::shared_ptr<const Vocabulary> vocabulary, const BowLoopDetectorOptions& options)
    : options_(options),
      vocabulary_(std::move(vocabulary)),
      database_(*vocabulary_),
      keyframes_since_loop_(options.keyframes_after_loop) {}

void BowLoopDetector::loop_closed(KeyframeId /*query*/) {
  keyframes_since_loop_ = 0;
  groups_.clear();
}

LoopCandidates BowLoopDetector::detect(const Map& map, KeyframeId query) {
  database_.sync(map);
  LoopCandidates result;
  ++keyframes_since_loop_;
  const Keyframe* keyframe = map.keyframe(query);
  if (keyframe == nullptr || !database_.contains(query)) {
    result.reason = "keyframe not in the map (culled or unknown)";
    return result;
  }
  if (static_cast<int>(database_.size()) < options_.min_keyframes_in_map) {
    result.reason = "map has " + std::to_string(database_.size()) + " keyframes (< " +
                    std::to_string(options_.min_keyframes_in_map) + ")";
    return result;
  }
  if (keyframes_since_loop_ <= options_.keyframes_after_loop) {
    result.reason = "within " + std::to_string(options_.keyframes_after_loop) + " keyframes of the last loop";
    return result;
  }

  const double min_score = covisible_min_score(map, *keyframe);
  const std::vector<PlaceCandidate> candidates = database_.loop_candidates(query, map, min_score, options_.query);
  if (candidates.empty()) {
    groups_.clear();
    result.reason = "no database candidate above the covisible minimum score " + std::to_string(min_score);
    return result;
  }
  consistent(map, candidates, groups_, result);
  return result;
}

// The worst score among the query's covisible neighbours: a candidate must look at least as much like
// the query as the keyframes it is known to see the same things with.
double BowLoopDetector::covisible_min_score(const Map& /*map*/, const Keyframe& keyframe) const {
  const BowVector& bow = *database_.bow(keyframe.id);
  double min_score = 1.0;
  for (const auto& [neighbour, weight] : keyframe.covisible) {
    const BowVector* other = database_.bow(neighbour);
    if (other == nullptr) continue;
    min_score = std::min(min_score, database_.vocabulary().score(bow, *other));
  }
  return min_score;
}

void BowLoopDetector::consistent(const Map& map, const std::vector<PlaceCandidate>& candidates,
                                 std::vector<ConsistentGroup>& groups, LoopCandidates& result) const {
  // Consistency: each candidate's group must share a keyframe with a group that was already a
  // candidate for the previous queries, `consistency_threshold` times in a row.
  std::vector<ConsistentGroup> current;
  std::vector<bool> previous_extended(groups.size(), false);
  for (const PlaceCandidate& candidate : candidates) {
    const std::set<KeyframeId> group = group_of(map, candidate.id);
    bool consistent_with_any = false;
    bool enough = false;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      if (!share_a_keyframe(group, groups[g].keyframes)) continue;
      consistent_with_any = true;
      const int consistency = groups[g].consistency + 1;
      if (!previous_extended[g]) {
        current.push_back({group, consistency});
        previous_extended[g] = true;
      }
      if (consistency >= options_.consistency_threshold) enough = true;
    }
    if (!consistent_with_any) current.push_back({group, 0});
    if (enough && std::find(result.keyframes.begin(), result.keyframes.end(), candidate.id) == result.keyframes.end()) {
      result.keyframes.push_back(candidate.id);
    }
  }
  groups = std::move(current);
  if (result.keyframes.empty()) {
    result.reason = std::to_string(candidates.size()) + " candidate(s), none consistent over " +
                    std::to_string(options_.consistency_threshold) + " keyframes yet";
  }
}

LoopCandidates BowLoopDetector::detect_merge(const Map& map, KeyframeId query, const std::set<KeyframeId>& other_maps) {
  database_.sync(map);
  LoopCandidates result;
  const Keyframe* keyframe = map.keyframe(query);
  if (keyframe == nullptr || !database_.contains(query)) {
    result.reason = "keyframe not in the map (culled or unknown)";
    return result;
  }
  std::vector<ConsistentGroup>& groups = merge_groups_[keyframe->map_id];
  if (other_maps.empty()) {
    groups.clear();
    result.reason = "no other map";
    return result;
  }
  // No minimum score (ORB-SLAM3's DetectNBestCandidates for merges): the loops' one, the worst score among
  // the query's covisible keyframes, is 1 for a new map's first keyframe and refuses everything, and the
  // scores of another map's keyframes at the same place are of the same order as that worst score
  // (MH01 halves: 0.01-0.04), so it refused them by chance. The verification (merge.min_matches) and the
  // consistency or the spatial confirmation guard the merge instead.
  constexpr double min_score = 0.0;
  const std::vector<PlaceCandidate> candidates =
      database_.merge_candidates(query, other_maps, map, min_score, options_.query);
  if (candidates.empty()) {
    groups.clear();
    result.reason = "no keyframe of another map shares enough words";
    return result;
  }
  consistent(map, candidates, groups, result);
  constexpr std::size_t kMaxUnconfirmed = 3;  // ORB-SLAM3's merge candidates per query
  for (const PlaceCandidate& candidate : candidates) {
    if (result.unconfirmed.size() == kMaxUnconfirmed) break;
    if (std::find(result.keyframes.begin(), result.keyframes.end(), candidate.id) == result.keyframes.end()) {
      result.unconfirmed.push_back(candidate.id);
    }
  }
  return result;
}

void BowLoopDetector::maps_merged(KeyframeId query) {
  loop_closed(query);
  merge_groups_.clear();
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> BowLoopDetector::match(const Map& map, KeyframeId query,
                                                                            KeyframeId candidate) const {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  const Keyframe* a = map.keyframe(query);
  const Keyframe* b = map.keyframe(candidate);
  const FeatureVector* a_features = database_.features(query);
  const FeatureVector* b_features = database_.features(candidate);
  if (a == nullptr || b == nullptr || a_features == nullptr || b_features == nullptr) return pairs;
  for (const BowPair& pair : match_keyframes_by_bow(*a, *a_features, *b, *b_features, map, options_.matching)) {
    pairs.emplace_back(pair.a, pair.b);
  }
  return pairs;
}

}  // namespace heslam
