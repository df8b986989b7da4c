// What one drawing of the viewer shows, as plain values copied out of the map model, so the drawing
// thread never touches the DDS thread's state: map points by category, keyframes, graph edges, the
// current camera, trajectories, the current frame and the tracking status.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"

namespace heslam::viewer {

enum class PointCategory { kMap, kRecent, kLoopMerged, kCulled };

struct ScenePoint {
  Eigen::Vector3d p_w;
  PointCategory category = PointCategory::kMap;
};

struct SceneEdge {
  Eigen::Vector3d from_w;
  Eigen::Vector3d to_w;
};

// A feature drawn on the 2D view, in rectified pixels.
struct SceneFeature {
  cv::Point2f uv_px;
  enum class Kind { kMapMatch, kStereoOnly, kProjectedMapPoint } kind = Kind::kMapMatch;
};

enum class TrackingStatus { kNone, kNotInitialized, kTracking, kLost, kRelocalized };
const char* to_string(TrackingStatus status);

struct Scene {
  std::vector<ScenePoint> points;
  std::vector<Pose3> keyframes_T_wc;  // keyframes not culled (one frustum each)
  std::vector<SceneEdge> covisibility;
  std::vector<SceneEdge> spanning_tree;
  bool has_camera = false;  // an odometry sample arrived
  Pose3 current_T_wc = Pose3::Identity();
  std::vector<Eigen::Vector3d> trajectory_w;       // estimated camera positions, frame by frame
  std::vector<std::int64_t> trajectory_stamps_ns;  // their frame stamps
  std::vector<Eigen::Vector3d> ground_truth_w;     // aligned to the estimate; empty without --gt
  PinholeStereo camera;                            // rectified model (frustum shape); zero until known
  // heslam-occupancy's newest 2D grid (map/occupancy_grid), drawn under the map in the top view; null
  // until one arrives. T_wg: its grid frame (z up) -> world.
  std::shared_ptr<const OccupancyGrid> occupancy;
  Pose3 occupancy_T_wg = Pose3::Identity();

  // The 2D view.
  bool has_frame = false;
  std::uint64_t frame_seq = 0;
  std::int64_t frame_stamp_ns = 0;
  cv::Mat raw_left;                                  // 8-bit grey, as published (not rectified)
  std::shared_ptr<const StereoRectifier> rectifier;  // from the calibration topic; null until it arrives
  bool frame_is_keyframe = false;                    // features are the keyframe's own keypoints
  std::vector<SceneFeature> features;
  TrackingStatus status = TrackingStatus::kNone;
  double frame_time_ms = 0.0;  // the frontend's "total" stage of this frame
  std::uint32_t tracked_points = 0;
  bool loop_flash = false;  // a loop correction arrived moments ago
  std::uint64_t loop_corrections = 0;

  // Counts.
  std::size_t map_keyframes = 0;  // keyframes not culled
  std::size_t map_points = 0;     // live points (culled ones excluded)
  std::uint64_t map_version = 0;  // the mapper's, as last received
};

}  // namespace heslam::viewer
