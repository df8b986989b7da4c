// Relocalization against the keyframe database's candidates (or, without one, the newest keyframes).
#include "components/core/tracking/relocalizer.hpp"

#include <functional>
#include <vector>

#include "components/core/solve/pnp_ransac.hpp"
#include "components/core/tracking/bow_search.hpp"
#include "components/core/tracking/local_map.hpp"
#include "components/core/tracking/optimize_frame.hpp"
#include "components/core/tracking/projection_search.hpp"

namespace heslam {
namespace {

// ORB-SLAM2 Relocalization: after PnP, too few inliers are topped up by a wide projection search
// (radius 10, then 3) before the final verdict.
constexpr float kWideSearchRadiusPx = 10.f;
constexpr float kNarrowSearchRadiusPx = 3.f;
constexpr int kMinPnpInliers = 10;
// Distinct RANSAC stream per (frame, keyframe): mixes the ids with a 64-bit odd constant.
constexpr std::uint64_t kSeedMix = 0x9e3779b97f4a7c15ULL;

// Writes the first matches between the keyframe's map points and the frame; returns how many.
using KeyframeMatcher = std::function<int(Frame&, const Keyframe&)>;

std::optional<Relocalization> try_keyframe(Frame& frame, Map& map, const Keyframe& keyframe,
                                           const PinholeStereo& camera, const TrackerOptions& options,
                                           const KeyframeMatcher& match) {
  const Pose3 T_wc_before = frame.T_wc;
  frame.clear_matches();
  const int matches = match(frame, keyframe);
  if (matches < options.min_relocalization_matches) {
    frame.clear_matches();
    return std::nullopt;
  }
  std::vector<PnpCorrespondence> correspondences;
  std::vector<std::size_t> keypoint_of;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] == kNoId) continue;
    const Keypoint& kp = frame.features.keypoints[i];
    correspondences.push_back({map.point(frame.point_ids[i])->p_w, kp.u_px, kp.v_px,
                               frame.features.pyramid.sigma2[static_cast<std::size_t>(kp.octave)]});
    keypoint_of.push_back(i);
  }
  PnpRansacOptions pnp_options;
  pnp_options.min_inliers = kMinPnpInliers;
  pnp_options.seed = options.ransac_seed ^ (frame.seq * kSeedMix) ^ keyframe.id;
  const auto pnp = PnpRansac(pnp_options).compute(camera, correspondences);
  if (!pnp) {
    frame.clear_matches();
    frame.T_wc = T_wc_before;
    return std::nullopt;
  }
  for (std::size_t k = 0; k < keypoint_of.size(); ++k) {
    if (!pnp->inlier[k]) frame.point_ids[keypoint_of[k]] = kNoId;
  }
  frame.T_wc = pnp->T_cw.inverse();
  optimize_frame_pose(frame, map, camera, options);
  int inliers = frame.discard_outliers();
  if (inliers < kMinPnpInliers) {
    frame.clear_matches();
    frame.T_wc = T_wc_before;
    return std::nullopt;
  }
  if (inliers < options.min_relocalization_inliers) {
    // Top up with the points of the keyframe's neighbourhood, projected with the recovered pose.
    const LocalMapSelection local = select_local_map(frame, map, options);
    search_local_points(frame, local.points, map, camera, kWideSearchRadiusPx, options);
    optimize_frame_pose(frame, map, camera, options);
    inliers = frame.discard_outliers();
    if (inliers < options.min_relocalization_inliers) {
      search_local_points(frame, local.points, map, camera, kNarrowSearchRadiusPx, options);
      optimize_frame_pose(frame, map, camera, options);
      inliers = frame.discard_outliers();
    }
  }
  if (inliers < options.min_relocalization_inliers) {
    frame.clear_matches();
    frame.T_wc = T_wc_before;
    return std::nullopt;
  }
  return Relocalization{keyframe.id, inliers};
}

}  // namespace

std::optional<Relocalization> relocalize(Frame& frame, Map& map, const PinholeStereo& camera,
                                         const TrackerOptions& options, const KeyframeDatabase* database) {
  int tried = 0;
  if (database != nullptr && !database->vocabulary().empty()) {
    BowVector bow;
    FeatureVector features;
    database->vocabulary().transform(frame.features.descriptors, bow, &features, kBowMatchLevelsUp);
    BowSearchOptions bow_options;
    bow_options.max_distance = options.descriptor_threshold_low;
    bow_options.ratio = options.relocalization_ratio;
    bow_options.check_orientation = options.check_orientation;
    for (const PlaceCandidate& candidate : database->relocalization_candidates(bow, map)) {
      const Keyframe* keyframe = map.keyframe(candidate.id);
      const FeatureVector* keyframe_features = database->features(candidate.id);
      if (keyframe == nullptr || keyframe->culled || keyframe_features == nullptr) continue;
      ++tried;
      const KeyframeMatcher by_bow = [&](Frame& f, const Keyframe& k) {
        return search_keyframe_by_bow(f, features, k, *keyframe_features, map, bow_options);
      };
      auto result = try_keyframe(frame, map, *keyframe, camera, options, by_bow);
      if (result) {
        result->candidates_tried = tried;
        return result;
      }
    }
  } else {
    const KeyframeMatcher brute_force = [&](Frame& f, const Keyframe& k) {
      return search_keyframe_brute_force(f, k, map, options.relocalization_ratio, options);
    };
    for (auto it = map.keyframes.rbegin(); it != map.keyframes.rend() && tried < options.relocalization_keyframes;
         ++it) {
      if (it->second.culled) continue;
      ++tried;
      auto result = try_keyframe(frame, map, it->second, camera, options, brute_force);
      if (result) {
        result->candidates_tried = tried;
        return result;
      }
    }
  }
  frame.clear_matches();
  return std::nullopt;
}

}  // namespace heslam
