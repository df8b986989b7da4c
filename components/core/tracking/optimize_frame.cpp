// Frame <-> motion-only BA glue.
#include "components/core/tracking/optimize_frame.hpp"

namespace heslam {
namespace {

// Keypoint i of the frame observing `point`.
PoseObservation make_observation(const Frame& frame, std::size_t i, const MapPoint& point) {
  const Keypoint& kp = frame.features.keypoints[i];
  PoseObservation obs;
  obs.p_w = point.p_w;
  obs.u_px = kp.u_px;
  obs.v_px = kp.v_px;
  obs.u_right_px = frame.features.has_stereo(i) ? frame.features.u_right_px[i] : -1.0;
  obs.inv_sigma2 = frame.features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)];
  return obs;
}

}  // namespace

std::vector<PoseObservation> frame_observations(const Frame& frame, const Map& map,
                                                std::vector<std::size_t>* keypoint_of) {
  std::vector<PoseObservation> observations;
  if (keypoint_of != nullptr) keypoint_of->clear();
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] == kNoId || frame.outlier[i]) continue;
    const MapPoint* point = map.point(frame.point_ids[i]);
    if (point == nullptr) continue;
    observations.push_back(make_observation(frame, i, *point));
    if (keypoint_of != nullptr) keypoint_of->push_back(i);
  }
  return observations;
}

int optimize_frame_pose(Frame& frame, const Map& map, const PinholeStereo& camera, const TrackerOptions& options) {
  // Matches of points the map no longer holds are dropped; the outlier flags are cleared, so every
  // other match becomes an observation (what frame_observations would give now, with one map lookup
  // per match instead of two).
  std::vector<std::size_t> keypoint_of;
  std::vector<PoseObservation> observations;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    frame.outlier[i] = false;
    if (frame.point_ids[i] == kNoId) continue;
    const MapPoint* point = map.point(frame.point_ids[i]);
    if (point == nullptr) {
      frame.point_ids[i] = kNoId;
      continue;
    }
    observations.push_back(make_observation(frame, i, *point));
    keypoint_of.push_back(i);
  }
  if (observations.empty()) return 0;
  MotionOnlyBaOptions ba;
  ba.rounds = options.pose_optimization_rounds;
  ba.iterations_per_round = options.pose_optimization_iterations;
  ba.disparity_sigma_ratio = options.disparity_sigma_ratio;
  const MotionOnlyBaResult result = optimize_pose(camera, observations, frame.T_cw(), ba);
  frame.T_wc = result.T_cw.inverse();
  for (std::size_t k = 0; k < keypoint_of.size(); ++k) frame.outlier[keypoint_of[k]] = result.outlier[k];
  return result.inliers;
}

}  // namespace heslam
