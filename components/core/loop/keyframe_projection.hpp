// Matching a map point to a keyframe's keypoints by projection from a given (e.g. loop-corrected)
// pose: ORB-SLAM2's projection test (in front, inside the image, inside the point's scale range
// with a little slack, seen within 60 degrees of its mean viewing direction), then the nearest
// descriptor among the keypoints near the projection at the predicted pyramid level. Shared by the
// loop verification's top-up and the loop correction's duplicate search.
#pragma once

#include <optional>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/match/feature_grid.hpp"

namespace heslam {

struct ProjectionMatchOptions {
  float radius_px = 4.f;             // times the predicted level's scale (ORB-SLAM2 fuse: 4, loop search: 10)
  int max_descriptor_distance = 50;  // ORB-SLAM2 TH_LOW
  double min_view_cos = 0.5;         // viewing direction within 60 degrees of the point's mean
};

// Where `point` would be seen from a camera at T_wc: its pixel and distance, or nullopt when the
// projection test fails (behind, outside the image, outside its scale range, too oblique).
struct PredictedView {
  Eigen::Vector2d uv_px;
  double distance_m = 0.0;
};
std::optional<PredictedView> predict_view(const MapPoint& point, const Pose3& T_wc, const PinholeStereo& camera,
                                          const ProjectionMatchOptions& options);

// The keypoint index of `kf` (seen from T_wc, `grid` built on its keypoints) that best matches
// `point`, or -1.
int best_projection_match(const MapPoint& point, const Keyframe& kf, const Pose3& T_wc, const FeatureGrid& grid,
                          const PinholeStereo& camera, const ProjectionMatchOptions& options);

}  // namespace heslam
