// The frame being tracked: its stereo features, the map point matched to each keypoint and its pose.
//
// A Frame lives inside the tracker only (the current and the last frame); what leaves the tracker is a
// TrackResult, and a Keyframe when the frame is promoted.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/feature/features.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/match/feature_grid.hpp"

namespace heslam {

struct Frame {
  std::int64_t stamp_ns = 0;
  std::uint64_t seq = 0;
  StereoFeatures features;
  FeatureGrid grid;                // keypoint positions binned for projection searches
  std::vector<PointId> point_ids;  // per keypoint: matched map point or kNoId
  std::vector<bool> outlier;       // per keypoint: rejected by the last pose optimization
  Pose3 T_wc = Pose3::Identity();

  Frame() = default;
  Frame(std::int64_t stamp, std::uint64_t sequence, StereoFeatures feats, const PinholeStereo& camera)
      : stamp_ns(stamp),
        seq(sequence),
        features(std::move(feats)),
        grid(features.keypoints, camera.width_px, camera.height_px),
        point_ids(features.size(), kNoId),
        outlier(features.size(), false) {}

  std::size_t size() const { return features.size(); }
  Pose3 T_cw() const { return T_wc.inverse(); }

  // Drops matches flagged as outliers; returns the number of matches left.
  int discard_outliers() {
    int kept = 0;
    for (std::size_t i = 0; i < point_ids.size(); ++i) {
      if (point_ids[i] == kNoId) continue;
      if (outlier[i]) {
        point_ids[i] = kNoId;
        outlier[i] = false;
      } else {
        ++kept;
      }
    }
    return kept;
  }
  void clear_matches() {
    std::fill(point_ids.begin(), point_ids.end(), kNoId);
    std::fill(outlier.begin(), outlier.end(), false);
  }
};

}  // namespace heslam
