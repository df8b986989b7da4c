// heslam messages -> ROS 2 messages (nav_msgs/Odometry, geometry_msgs/PoseStamped, nav_msgs/Path,
// sensor_msgs/PointCloud2), DDS-free so they are unit-tested on known values.
//
// Frames: poses stay heslam's T_wc (camera -> world) in heslam's world frame, which is the first
// camera's optical frame (x right, y down, z forward), named `frames.world`; the camera frame is
// `frames.camera`. The pose covariance is the tracker's (ros_pose_covariance); the twist is not
// estimated: all zeros.
//
// Each *Message class holds the C struct and the storage its sequences point into; strings point
// into `frames`, which must outlive the message. Build one, write get(), drop it.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "runtime/messages.hpp"
#include "tools/ros2_bridge/ros2_messages.hpp"

namespace heslam::ros2 {

struct Frames {
  std::string world = "heslam_world";    // header.frame_id of the odometry, pose, path and cloud
  std::string camera = "heslam_camera";  // Odometry.child_frame_id; base -> camera on /tf_static
  // REP 105 (tf_tree.hpp): map -> odom -> base on /tf; map -> world and base -> camera on /tf_static.
  std::string map = "map";
  std::string odom = "odom";
  std::string base = "base_link";
};

// nav_msgs/Odometry's pose.covariance (row-major 6x6 over x, y, z, rotation about X, Y, Z, in the
// header.frame_id's axes) from heslam's Odometry.T_wc_covariance (upper triangle over rotation, then
// position, in the world's axes, idl/odometry.idl): the same numbers in ROS 2's order.
std::array<double, 36> ros_pose_covariance(const double (&T_wc_covariance)[21]);

// builtin_interfaces/Time of a stamp in ns (nanosec always in [0, 1e9), also for negative stamps).
Time to_time(std::int64_t stamp_ns);
Pose to_pose(const msg::Pose& pose);

class OdometryMessage {
 public:
  OdometryMessage(const msg::Odometry& odometry, const Frames& frames);
  OdometryMessage(const OdometryMessage&) = delete;
  OdometryMessage& operator=(const OdometryMessage&) = delete;
  const Odometry& get() const { return message_; }

 private:
  Odometry message_{};
};

class PoseStampedMessage {
 public:
  PoseStampedMessage(std::int64_t stamp_ns, const msg::Pose& T_wc, const Frames& frames);
  PoseStampedMessage(const PoseStampedMessage&) = delete;
  PoseStampedMessage& operator=(const PoseStampedMessage&) = delete;
  const PoseStamped& get() const { return message_; }

 private:
  PoseStamped message_{};
};

// One keyframe of the trajectory: its stamp and newest pose.
struct KeyframePose {
  std::int64_t stamp_ns = 0;
  msg::Pose T_wc{};
};

// nav_msgs/Path of the keyframes in stamp order; header stamp = the newest keyframe's.
class PathMessage {
 public:
  PathMessage(std::vector<KeyframePose> keyframes, const Frames& frames);
  PathMessage(const PathMessage&) = delete;
  PathMessage& operator=(const PathMessage&) = delete;
  const Path& get() const { return message_; }

 private:
  std::vector<PoseStamped> poses_;
  Path message_{};
};

// sensor_msgs/PointCloud2: one row of float32 x, y, z (12 bytes per point, little-endian, dense).
class PointCloudMessage {
 public:
  PointCloudMessage(std::int64_t stamp_ns, const std::vector<std::array<double, 3>>& points_w_m, const Frames& frames);
  // Points already in `frame_id` (which must outlive the message).
  PointCloudMessage(std::int64_t stamp_ns, const std::vector<std::array<double, 3>>& points,
                    const std::string& frame_id);
  PointCloudMessage(const PointCloudMessage&) = delete;
  PointCloudMessage& operator=(const PointCloudMessage&) = delete;
  const PointCloud2& get() const { return message_; }

  static constexpr std::uint32_t kPointStep = 12;

 private:
  std::vector<PointField> fields_;
  std::vector<std::uint8_t> data_;
  PointCloud2 message_{};
};

// nav_msgs/OccupancyGrid of heslam-occupancy's grid (validated: occupancy::check_grid) in frames.map:
// info.origin = T_map_world T_wg (origin_i, origin_j, 0) x resolution, data as the grid's cells (free 0,
// occupied 100, unknown -1), header and map_load_time stamped with the grid's newest keyframe.
class OccupancyGridMessage {
 public:
  OccupancyGridMessage(const msg::OccupancyGrid2D& grid, const Pose3& T_map_world, const Frames& frames);
  OccupancyGridMessage(const OccupancyGridMessage&) = delete;
  OccupancyGridMessage& operator=(const OccupancyGridMessage&) = delete;
  const OccupancyGrid& get() const { return message_; }

 private:
  std::vector<std::int8_t> data_;
  OccupancyGrid message_{};
};

// One geometry_msgs/TransformStamped: the child's pose in the parent. The names must outlive the message.
struct NamedTransform {
  const std::string& parent;
  const std::string& child;
  Pose3 T_parent_child;
};

Transform to_transform(const Pose3& T_parent_child);

// tf2_msgs/TFMessage: the transforms, all stamped stamp_ns.
class TfMessage {
 public:
  TfMessage(std::int64_t stamp_ns, const std::vector<NamedTransform>& transforms);
  TfMessage(const TfMessage&) = delete;
  TfMessage& operator=(const TfMessage&) = delete;
  const TFMessage& get() const { return message_; }

 private:
  std::vector<TransformStamped> transforms_;
  TFMessage message_{};
};

}  // namespace heslam::ros2
