// heslam-ros2-bridge: republishes heslam's odometry, keyframe trajectory and map points on ROS 2 topic
// names with ROS 2's wire types, so ROS 2 tools (rviz2, ros2 topic echo, rosbag2) on the same DDS
// domain see them without any ROS code in heslam (docs/ros2.md).
//
//   heslam-odometry          -> rt/<ros_namespace>/odometry             nav_msgs/Odometry (tracked frames)
//                            -> rt/<ros_namespace>/pose                 geometry_msgs/PoseStamped
//   map/keyframes + states   -> rt/<ros_namespace>/keyframe_trajectory  nav_msgs/Path (transient local)
//   map/points               -> rt/<ros_namespace>/map_points           sensor_msgs/PointCloud2 (transient local)
//   odometry (T_wc, T_oc)    -> rt/tf         tf2_msgs/TFMessage: map -> odom -> base_link (REP 105, tf_tree.hpp)
//   camera/calibration       -> rt/tf_static  tf2_msgs/TFMessage: base_link -> camera, map -> world (transient local)
//   map/occupancy_grid       -> rt/map        nav_msgs/OccupancyGrid in map_frame (transient local, as map_server)
//   map/dense_cloud          -> rt/<ros_namespace>/dense_cloud  sensor_msgs/PointCloud2 in map_frame (transient local)
//
// Config fields (all optional): ros_namespace ("heslam"), world_frame ("heslam_world"),
// camera_frame ("heslam_camera"), map_frame ("map"), odom_frame ("odom"), base_frame ("base_link"),
// publish_period_s (1.0: how often a changed path / cloud is sent).
#pragma once

#include <array>
#include <chrono>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "runtime/component.hpp"
#include "tools/ros2_bridge/ros2_conversions.hpp"
#include "tools/ros2_bridge/ros2_writer.hpp"

namespace heslam::ros2 {

struct BridgeOptions {
  std::string ros_namespace = "heslam";
  Frames frames;
  double publish_period_s = 1.0;

  // Throws std::runtime_error naming the field on a bad value.
  static BridgeOptions from(const runtime::Config& config);
};

class Ros2Bridge : public runtime::Component {
 public:
  explicit Ros2Bridge(const runtime::CommonArgs& args);

  // --help after the common flags: the topics it reads and writes, and its config fields.
  static std::string help_notes();

 private:
  void configure(const runtime::Config& config) override;
  void run() override;

  void on_odometry(const msg::Odometry& odometry);
  void on_calibration(const msg::StereoCalibration& calibration);
  // What a frame's TF needs of its odometry (held until the calibration gives the body frame).
  struct TfFrame {
    std::int64_t stamp_ns = 0;
    std::uint64_t seq = 0;
    msg::Pose T_wc{};
    msg::Pose T_oc{};
  };
  void publish_tf(const TfFrame& frame);
  void publish_static_tf();
  // Inertial runs: takes the odometry's gravity; map turns (tf_static again) when it moved noticeably.
  void take_gravity(const msg::Odometry& odometry);
  // map from the body at the first keyframe: the gravity alignment once there is a gravity, else identity.
  Pose3 T_map_b0() const;
  void publish_map_if_changed();
  // heslam-occupancy's grid and cloud, in the map frame: held until a calibration gave T_map_world.
  void publish_occupancy();

  struct KeyframeEntry {
    std::optional<std::int64_t> stamp_ns;  // from map/keyframes
    msg::Pose T_wc{};                      // newest: the keyframe's, then its states'
    bool culled = false;
  };

  BridgeOptions options_;
  std::optional<Ros2Writer<Odometry>> odometry_writer_;
  std::optional<Ros2Writer<PoseStamped>> pose_writer_;
  std::optional<Ros2Writer<Path>> path_writer_;
  std::optional<Ros2Writer<PointCloud2>> cloud_writer_;
  std::optional<Ros2Writer<TFMessage>> tf_writer_;
  std::optional<Ros2Writer<TFMessage>> tf_static_writer_;
  std::optional<Ros2Writer<OccupancyGrid>> occupancy_grid_writer_;
  std::optional<Ros2Writer<PointCloud2>> dense_cloud_writer_;
  std::optional<Pose3> T_B_rect_;  // rectified left camera -> body, from the newest calibration
  // Frames tracked before the calibration arrived (discovery may bring a frontend's odometry before the
  // replay's calibration): their TF goes out once it does; the oldest beyond kHeldTfFrames are dropped.
  std::deque<TfFrame> tf_held_;
  std::optional<Eigen::Vector3d> gravity_w_;  // inertial runs: the gravity map is aligned with (world)
  std::map<std::uint64_t, KeyframeEntry> keyframes_;
  std::map<std::uint64_t, std::array<double, 3>> points_w_m_;
  std::int64_t newest_stamp_ns_ = 0;
  bool path_changed_ = false;
  bool cloud_changed_ = false;
  // The newest occupancy grid / dense cloud not republished yet (copied out of the DDS sample).
  struct PendingGrid {
    msg::OccupancyGrid2D header{};  // every field but cells
    std::vector<std::uint8_t> cells;
  };
  std::optional<PendingGrid> pending_grid_;
  std::optional<std::pair<std::int64_t, std::vector<std::array<double, 3>>>> pending_dense_cloud_;
};

}  // namespace heslam::ros2
