// Matching two images' features word by word (ORB-SLAM2 SearchByBoW): only features filed under the
// same vocabulary node (a feature vector at kBowMatchLevelsUp) are compared, so the search needs no
// pose and costs a fraction of brute force. One core, two uses:
//   - a keyframe's map points into a frame's free keypoints (relocalization);
//   - keyframe against keyframe, as index pairs (the loop closer).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "components/core/feature/features.hpp"
#include "components/core/map/map.hpp"
#include "components/core/place/bow_vector.hpp"
#include "components/core/tracking/frame.hpp"

namespace heslam {

struct BowSearchOptions {
  int max_distance = 50;  // ORB-SLAM2 TH_LOW: a word shares coarse structure only, so be strict
  float ratio = 0.75f;    // best < ratio x second best (ORB-SLAM2: 0.75 relocalization and loops, 0.7 reference)
  bool check_orientation = true;  // keep matches in the 3 dominant rotation-histogram bins
};

// One image's side of a search. `usable[i]` != 0: feature i may be matched.
struct BowSide {
  const FeatureVector& features;
  std::span<const Descriptor> descriptors;
  std::span<const Keypoint> keypoints;
  std::span<const std::uint8_t> usable;
};

struct BowPair {
  std::uint32_t a = 0;  // feature index in side a
  std::uint32_t b = 0;  // feature index in side b
};

// The core: for each usable feature of `a` (node by node, ascending), the nearest usable and not yet
// taken feature of `b` in the same node, kept when within max_distance and clearly better than the
// second nearest; then the rotation check. Each b feature is matched at most once. Ordered by a.
std::vector<BowPair> match_by_bow(const BowSide& a, const BowSide& b, const BowSearchOptions& options);

// The keyframe's map points (not culled) into the frame's free keypoints: writes Frame::point_ids,
// returns how many matches it added.
int search_keyframe_by_bow(Frame& frame, const FeatureVector& frame_features, const Keyframe& keyframe,
                           const FeatureVector& keyframe_features, const Map& map, const BowSearchOptions& options);

// Keyframe against keyframe: pairs (keypoint of a, keypoint of b) where both observe a map point
// (not culled). ORB-SLAM2 SearchByBoW(KF1, KF2), for the loop closer's Sim3 / SE(3) solving.
std::vector<BowPair> match_keyframes_by_bow(const Keyframe& a, const FeatureVector& a_features, const Keyframe& b,
                                            const FeatureVector& b_features, const Map& map,
                                            const BowSearchOptions& options);

}  // namespace heslam
