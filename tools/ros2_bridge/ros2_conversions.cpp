// heslam -> ROS 2 message conversion (see ros2_conversions.hpp for frames and units).
#include "tools/ros2_bridge/ros2_conversions.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#include <Eigen/Geometry>

#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::ros2 {

namespace {

constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;

// PointCloud2 carries its byte order; heslam writes the host's, which must be little-endian to say so.
static_assert(std::endian::native == std::endian::little, "PointCloudMessage writes is_bigendian = false");

Header header(std::int64_t stamp_ns, const std::string& frame_id) {
  Header h{};
  h.stamp = to_time(stamp_ns);
  h.frame_id = runtime::borrow(frame_id);
  return h;
}

Header header(std::int64_t stamp_ns, const Frames& frames) { return header(stamp_ns, frames.world); }

}  // namespace

Time to_time(std::int64_t stamp_ns) {
  std::int64_t sec = stamp_ns / kNanosecondsPerSecond;
  std::int64_t nanosec = stamp_ns % kNanosecondsPerSecond;
  if (nanosec < 0) {
    nanosec += kNanosecondsPerSecond;
    sec -= 1;
  }
  return Time{static_cast<std::int32_t>(sec), static_cast<std::uint32_t>(nanosec)};
}

Pose to_pose(const msg::Pose& pose) {
  Pose out{};
  out.position = {pose.position_m[0], pose.position_m[1], pose.position_m[2]};
  out.orientation = {pose.orientation_xyzw[0], pose.orientation_xyzw[1], pose.orientation_xyzw[2],
                     pose.orientation_xyzw[3]};
  return out;
}

std::array<double, 36> ros_pose_covariance(const double (&T_wc_covariance)[21]) {
  // heslam's index of each ROS 2 index: ROS 2 x y z rx ry rz = heslam 3 4 5 0 1 2.
  constexpr int kHeslamIndex[6] = {3, 4, 5, 0, 1, 2};
  double full[6][6];
  int k = 0;
  for (int row = 0; row < 6; ++row) {
    for (int col = row; col < 6; ++col) full[row][col] = full[col][row] = T_wc_covariance[k++];
  }
  std::array<double, 36> out{};
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 6; ++col)
      out[static_cast<std::size_t>(6 * row + col)] = full[kHeslamIndex[row]][kHeslamIndex[col]];
  }
  return out;
}

OdometryMessage::OdometryMessage(const msg::Odometry& odometry, const Frames& frames) {
  message_.header = header(odometry.stamp_ns, frames);
  message_.child_frame_id = runtime::borrow(frames.camera);
  message_.pose.pose = to_pose(odometry.T_wc);
  const std::array<double, 36> covariance = ros_pose_covariance(odometry.T_wc_covariance);
  std::copy(covariance.begin(), covariance.end(), message_.pose.covariance);
}

PoseStampedMessage::PoseStampedMessage(std::int64_t stamp_ns, const msg::Pose& T_wc, const Frames& frames) {
  message_.header = header(stamp_ns, frames);
  message_.pose = to_pose(T_wc);
}

PathMessage::PathMessage(std::vector<KeyframePose> keyframes, const Frames& frames) {
  std::stable_sort(keyframes.begin(), keyframes.end(),
                   [](const KeyframePose& a, const KeyframePose& b) { return a.stamp_ns < b.stamp_ns; });
  poses_.reserve(keyframes.size());
  for (const KeyframePose& keyframe : keyframes) {
    PoseStamped pose{};
    pose.header = header(keyframe.stamp_ns, frames);
    pose.pose = to_pose(keyframe.T_wc);
    poses_.push_back(pose);
  }
  message_.header = header(keyframes.empty() ? 0 : keyframes.back().stamp_ns, frames);
  runtime::borrow(message_.poses, poses_);
}

PointCloudMessage::PointCloudMessage(std::int64_t stamp_ns, const std::vector<std::array<double, 3>>& points_w_m,
                                     const Frames& frames)
    : PointCloudMessage(stamp_ns, points_w_m, frames.world) {}

PointCloudMessage::PointCloudMessage(std::int64_t stamp_ns, const std::vector<std::array<double, 3>>& points_w_m,
                                     const std::string& frame_id) {
  static const std::string kNames[3] = {"x", "y", "z"};
  for (std::uint32_t k = 0; k < 3; ++k) {
    fields_.push_back(PointField{runtime::borrow(kNames[k]), 4 * k, kPointFieldFloat32, 1});
  }
  data_.resize(points_w_m.size() * kPointStep);
  for (std::size_t i = 0; i < points_w_m.size(); ++i) {
    const float xyz[3] = {static_cast<float>(points_w_m[i][0]), static_cast<float>(points_w_m[i][1]),
                          static_cast<float>(points_w_m[i][2])};
    std::memcpy(data_.data() + i * kPointStep, xyz, sizeof xyz);
  }
  message_.header = header(stamp_ns, frame_id);
  message_.height = 1;
  message_.width = static_cast<std::uint32_t>(points_w_m.size());
  runtime::borrow(message_.fields, fields_);
  message_.is_bigendian = false;
  message_.point_step = kPointStep;
  message_.row_step = kPointStep * message_.width;
  runtime::borrow(message_.data, data_);
  message_.is_dense = true;  // map points are never NaN
}

OccupancyGridMessage::OccupancyGridMessage(const msg::OccupancyGrid2D& grid, const Pose3& T_map_world,
                                           const Frames& frames) {
  const auto cells = runtime::view(grid.cells);
  data_.resize(cells.size());
  // The wire values are nav_msgs' already (255 is -1 as int8).
  std::memcpy(data_.data(), cells.data(), cells.size());
  Pose3 T_grid_origin = Pose3::Identity();
  T_grid_origin.translation() = Eigen::Vector3d(grid.origin_i, grid.origin_j, 0.0) * grid.resolution_m;
  const Pose3 T_map_origin = T_map_world * messages::to_pose(grid.T_wg) * T_grid_origin;
  message_.header = header(grid.stamp_ns, frames.map);
  message_.info.map_load_time = to_time(grid.stamp_ns);
  message_.info.resolution = static_cast<float>(grid.resolution_m);
  message_.info.width = grid.width;
  message_.info.height = grid.height;
  const Eigen::Vector3d t = T_map_origin.translation();
  const Eigen::Quaterniond q(T_map_origin.rotation());
  message_.info.origin.position = {t.x(), t.y(), t.z()};
  message_.info.origin.orientation = {q.x(), q.y(), q.z(), q.w()};
  runtime::borrow(message_.data, data_);
}

Transform to_transform(const Pose3& T_parent_child) {
  const Eigen::Vector3d t = T_parent_child.translation();
  const Eigen::Quaterniond q(T_parent_child.rotation());
  Transform out{};
  out.translation = {t.x(), t.y(), t.z()};
  out.rotation = {q.x(), q.y(), q.z(), q.w()};
  return out;
}

TfMessage::TfMessage(std::int64_t stamp_ns, const std::vector<NamedTransform>& transforms) {
  transforms_.reserve(transforms.size());
  for (const NamedTransform& named : transforms) {
    TransformStamped stamped{};
    stamped.header = header(stamp_ns, named.parent);
    stamped.child_frame_id = runtime::borrow(named.child);
    stamped.transform = to_transform(named.T_parent_child);
    transforms_.push_back(stamped);
  }
  runtime::borrow(message_.transforms, transforms_);
}

}  // namespace heslam::ros2
