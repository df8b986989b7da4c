// Word-by-word descriptor matching between two images' feature vectors.
#include "components/core/tracking/bow_search.hpp"

#include <algorithm>
#include <limits>

#include "components/core/tracking/rotation_histogram.hpp"

namespace heslam {
namespace {

// Features of a keyframe that observe a live map point.
std::vector<std::uint8_t> observing(const Keyframe& keyframe, const Map& map) {
  std::vector<std::uint8_t> usable(keyframe.point_ids.size(), 0);
  for (std::size_t i = 0; i < keyframe.point_ids.size(); ++i) {
    const MapPoint* point = map.point(keyframe.point_ids[i]);
    usable[i] = point != nullptr && !point->culled ? 1 : 0;
  }
  return usable;
}

void match_node(const BowSide& a, const std::vector<std::uint32_t>& a_indices, const BowSide& b,
                const std::vector<std::uint32_t>& b_indices, const BowSearchOptions& options,
                std::vector<std::uint8_t>& b_taken, std::vector<BowPair>& pairs) {
  for (const std::uint32_t ia : a_indices) {
    if (ia >= a.usable.size() || a.usable[ia] == 0) continue;
    int best = std::numeric_limits<int>::max();
    int second = std::numeric_limits<int>::max();
    std::uint32_t best_b = 0;
    for (const std::uint32_t ib : b_indices) {
      if (ib >= b.usable.size() || b.usable[ib] == 0 || b_taken[ib] != 0) continue;
      const int distance = hamming_distance(a.descriptors[ia], b.descriptors[ib]);
      if (distance < best) {
        second = best;
        best = distance;
        best_b = ib;
      } else if (distance < second) {
        second = distance;
      }
    }
    if (best > options.max_distance) continue;
    if (static_cast<float>(best) >= options.ratio * static_cast<float>(second)) continue;
    b_taken[best_b] = 1;
    pairs.push_back({ia, best_b});
  }
}

}  // namespace

std::vector<BowPair> match_by_bow(const BowSide& a, const BowSide& b, const BowSearchOptions& options) {
  std::vector<BowPair> pairs;
  std::vector<std::uint8_t> b_taken(b.descriptors.size(), 0);
  // Both node lists are sorted by node id: walk them together.
  auto ia = a.features.nodes.begin();
  auto ib = b.features.nodes.begin();
  while (ia != a.features.nodes.end() && ib != b.features.nodes.end()) {
    if (ia->first < ib->first) {
      ++ia;
    } else if (ib->first < ia->first) {
      ++ib;
    } else {
      match_node(a, ia->second, b, ib->second, options, b_taken, pairs);
      ++ia;
      ++ib;
    }
  }
  if (options.check_orientation && !pairs.empty()) {
    RotationHistogram histogram;
    for (std::size_t m = 0; m < pairs.size(); ++m) {
      histogram.add(a.keypoints[pairs[m].a].angle_deg, b.keypoints[pairs[m].b].angle_deg, static_cast<int>(m));
    }
    std::vector<std::uint8_t> rejected(pairs.size(), 0);
    for (const int m : histogram.rejected()) rejected[static_cast<std::size_t>(m)] = 1;
    std::size_t kept = 0;
    for (std::size_t m = 0; m < pairs.size(); ++m) {
      if (rejected[m] == 0) pairs[kept++] = pairs[m];
    }
    pairs.resize(kept);
  }
  std::sort(pairs.begin(), pairs.end(), [](const BowPair& x, const BowPair& y) { return x.a < y.a; });
  return pairs;
}

int search_keyframe_by_bow(Frame& frame, const FeatureVector& frame_features, const Keyframe& keyframe,
                           const FeatureVector& keyframe_features, const Map& map, const BowSearchOptions& options) {
  const std::vector<std::uint8_t> keyframe_usable = observing(keyframe, map);
  std::vector<std::uint8_t> frame_free(frame.size(), 0);
  for (std::size_t i = 0; i < frame.size(); ++i) frame_free[i] = frame.point_ids[i] == kNoId ? 1 : 0;
  const BowSide a{keyframe_features, keyframe.features.descriptors, keyframe.features.keypoints, keyframe_usable};
  const BowSide b{frame_features, frame.features.descriptors, frame.features.keypoints, frame_free};
  const std::vector<BowPair> pairs = match_by_bow(a, b, options);
  for (const BowPair& pair : pairs) frame.point_ids[pair.b] = keyframe.point_ids[pair.a];
  return static_cast<int>(pairs.size());
}

std::vector<BowPair> match_keyframes_by_bow(const Keyframe& a, const FeatureVector& a_features, const Keyframe& b,
                                            const FeatureVector& b_features, const Map& map,
                                            const BowSearchOptions& options) {
  const std::vector<std::uint8_t> a_usable = observing(a, map);
  const std::vector<std::uint8_t> b_usable = observing(b, map);
  return match_by_bow({a_features, a.features.descriptors, a.features.keypoints, a_usable},
                      {b_features, b.features.descriptors, b.features.keypoints, b_usable}, options);
}

}  // namespace heslam
