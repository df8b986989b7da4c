// C++ names for the ROS 2 wire types of idl/ros2_messages.idl (generated C structs). They are not
// heslam messages: no schema_version, no topic table; the bridge names their topics the ROS 2 way
// ("rt/" + ROS topic name).
#pragma once

#include <cstdint>
#include <string>

#include "ros2_idl/ros2_messages.h"

namespace heslam::ros2 {

using Time = builtin_interfaces_msg_dds__Time_;
using Header = std_msgs_msg_dds__Header_;
using Pose = geometry_msgs_msg_dds__Pose_;
using PoseStamped = geometry_msgs_msg_dds__PoseStamped_;
using Odometry = nav_msgs_msg_dds__Odometry_;
using Path = nav_msgs_msg_dds__Path_;
using PointField = sensor_msgs_msg_dds__PointField_;
using PointCloud2 = sensor_msgs_msg_dds__PointCloud2_;
using Transform = geometry_msgs_msg_dds__Transform_;
using TransformStamped = geometry_msgs_msg_dds__TransformStamped_;
using TFMessage = tf2_msgs_msg_dds__TFMessage_;
using Image = sensor_msgs_msg_dds__Image_;
using CameraInfo = sensor_msgs_msg_dds__CameraInfo_;
using MapMetaData = nav_msgs_msg_dds__MapMetaData_;
using OccupancyGrid = nav_msgs_msg_dds__OccupancyGrid_;
using Imu = sensor_msgs_msg_dds__Imu_;

// sensor_msgs/PointField datatype constant for float32.
inline constexpr std::uint8_t kPointFieldFloat32 = 7;

// "rt/<name>": the DDS topic ROS 2 uses for the ROS topic "/<name>" (no leading slash in `name`).
inline std::string ros2_topic(const std::string& ros_name) { return "rt/" + ros_name; }

}  // namespace heslam::ros2
