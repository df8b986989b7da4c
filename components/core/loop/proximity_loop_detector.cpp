// Proximity loop candidates and brute-force descriptor matching (see proximity_loop_detector.hpp).
#include "components/core/loop/proximity_loop_detector.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

namespace heslam {
namespace {

constexpr double kDegreesToRadians = 3.14159265358979323846 / 180.0;

}  // namespace

void ProximityLoopDetector::loop_closed(KeyframeId /*query*/) { keyframes_since_loop_ = 0; }

LoopCandidates ProximityLoopDetector::detect(const Map& map, KeyframeId query) {
  LoopCandidates result;
  ++keyframes_since_loop_;
  const Keyframe* keyframe = map.keyframe(query);
  if (keyframe == nullptr || keyframe->culled) {
    result.reason = "keyframe not in the map (culled or unknown)";
    return result;
  }
  int live = 0;
  for (const auto& [id, kf] : map.keyframes) live += kf.culled ? 0 : 1;
  if (live < options_.min_keyframes_in_map) {
    result.reason =
        "map has " + std::to_string(live) + " keyframes (< " + std::to_string(options_.min_keyframes_in_map) + ")";
    return result;
  }
  if (keyframes_since_loop_ <= options_.keyframes_after_loop) {
    result.reason = "within " + std::to_string(options_.keyframes_after_loop) + " keyframes of the last loop";
    return result;
  }

  // Path length up to each keyframe, in creation (id) order, over live and culled keyframes alike.
  std::map<KeyframeId, double> path_m;
  double travelled = 0.0;
  const Keyframe* previous = nullptr;
  for (const auto& [id, kf] : map.keyframes) {
    if (previous != nullptr) travelled += (kf.T_wc.translation() - previous->T_wc.translation()).norm();
    path_m[id] = travelled;
    previous = &kf;
    if (id == query) break;
  }
  std::set<KeyframeId> excluded{query};
  for (const auto& [neighbour, weight] : keyframe->covisible) excluded.insert(neighbour);

  const Eigen::Vector3d centre = keyframe->T_wc.translation();
  const Eigen::Vector3d axis = keyframe->T_wc.rotation().col(2);
  const double min_cos = std::cos(options_.max_view_angle_deg * kDegreesToRadians);
  std::vector<std::pair<double, KeyframeId>> near;
  for (const auto& [id, kf] : map.keyframes) {
    if (id >= query) break;
    if (kf.culled || excluded.count(id) != 0) continue;
    const double since = path_m[query] - path_m[id];
    if (since < options_.min_path_since_m) continue;
    const double radius = std::min(options_.max_radius_m, options_.base_radius_m + options_.drift_ratio * since);
    const double distance = (kf.T_wc.translation() - centre).norm();
    if (distance > radius) continue;
    if (kf.T_wc.rotation().col(2).dot(axis) < min_cos) continue;
    near.emplace_back(distance, id);
  }
  std::sort(near.begin(), near.end());
  for (std::size_t i = 0; i < near.size() && static_cast<int>(i) < options_.max_candidates; ++i) {
    result.keyframes.push_back(near[i].second);
  }
  if (result.keyframes.empty()) result.reason = "no old keyframe within the drift radius looking the same way";
  return result;
}

LoopCandidates ProximityLoopDetector::detect_merge(const Map& map, KeyframeId query,
                                                   const std::set<KeyframeId>& other_maps) {
  LoopCandidates result;
  const Keyframe* keyframe = map.keyframe(query);
  if (keyframe == nullptr || keyframe->culled) {
    result.reason = "keyframe not in the map (culled or unknown)";
    return result;
  }
  if (other_maps.empty()) {
    result.reason = "no other map";
    return result;
  }
  // Round robin from after the cursor, wrapping once.
  std::vector<std::pair<int, KeyframeId>> scored;  // (-matches, id): most matches first, ties by id
  auto it = other_maps.upper_bound(merge_cursor_);
  const std::size_t budget =
      std::min(other_maps.size(), static_cast<std::size_t>(std::max(1, options_.merge_keyframes_per_query)));
  for (std::size_t scanned = 0; scanned < budget; ++scanned) {
    if (it == other_maps.end()) it = other_maps.begin();
    const KeyframeId candidate = *it++;
    merge_cursor_ = candidate;
    const Keyframe* other = map.keyframe(candidate);
    if (other == nullptr || other->culled) continue;
    const int matches = static_cast<int>(match(map, query, candidate).size());
    if (matches >= options_.merge_min_matches) scored.emplace_back(-matches, candidate);
  }
  std::sort(scored.begin(), scored.end());
  for (std::size_t i = 0; i < scored.size() && static_cast<int>(i) < options_.max_candidates; ++i) {
    result.keyframes.push_back(scored[i].second);
  }
  if (result.keyframes.empty()) {
    result.reason = "none of " + std::to_string(budget) + " keyframes of other maps scanned has " +
                    std::to_string(options_.merge_min_matches) + " descriptor matches";
  }
  return result;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> ProximityLoopDetector::match(const Map& map, KeyframeId query,
                                                                                  KeyframeId candidate) const {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  const Keyframe* a = map.keyframe(query);
  const Keyframe* b = map.keyframe(candidate);
  if (a == nullptr || b == nullptr) return pairs;
  const auto observes_live_point = [&map](const Keyframe& kf, std::size_t i) {
    const MapPoint* point = kf.point_ids[i] == kNoId ? nullptr : map.point(kf.point_ids[i]);
    return point != nullptr && !point->culled;
  };
  std::vector<int> best_for_b(b->features.size(), std::numeric_limits<int>::max());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> tentative;
  for (std::size_t i = 0; i < a->features.size(); ++i) {
    if (!observes_live_point(*a, i)) continue;
    int best = std::numeric_limits<int>::max();
    int second = std::numeric_limits<int>::max();
    std::size_t best_j = 0;
    for (std::size_t j = 0; j < b->features.size(); ++j) {
      if (!observes_live_point(*b, j)) continue;
      const int d = hamming_distance(a->features.descriptors[i], b->features.descriptors[j]);
      if (d < best) {
        second = best;
        best = d;
        best_j = j;
      } else if (d < second) {
        second = d;
      }
    }
    if (best > options_.max_descriptor_distance) continue;
    if (static_cast<float>(best) >= options_.ratio * static_cast<float>(second)) continue;
    tentative.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(best_j));
    best_for_b[best_j] = std::min(best_for_b[best_j], best);
  }
  // Each candidate keypoint once: the closest descriptor wins (ties: the first query keypoint).
  std::vector<bool> used(b->features.size(), false);
  for (const auto& [i, j] : tentative) {
    if (used[j] || hamming_distance(a->features.descriptors[i], b->features.descriptors[j]) != best_for_b[j]) continue;
    used[j] = true;
    pairs.emplace_back(i, j);
  }
  return pairs;
}

}  // namespace heslam
