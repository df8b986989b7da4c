// heslam-ros2-bridge: heslam topics in, ROS 2 topics out (see ros2_bridge.hpp).
#include "tools/ros2_bridge/ros2_bridge.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/pose.hpp"
#include "components/occupancy/occupancy_messages.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"
#include "tools/ros2_bridge/tf_tree.hpp"

namespace heslam::ros2 {

namespace {

// ROS 2's default QoS profile for a stream: reliable, volatile, keep last 10 (rclcpp's default).
constexpr int kRosDefaultDepth = 10;
constexpr double kMinPublishPeriod_s = 0.05;
constexpr double kMaxPublishPeriod_s = 60.0;
// Odometry.T_oc of a frontend is normalised; one zeroed or far off did not come from a frontend.
constexpr double kUnitQuaternionTolerance = 1e-6;
// Inertial runs: a gravity outside this range (m/s^2) is not one (the Earth's is 9.78..9.83); map turns
// again when the gravity estimate moved more than this from the one it is aligned with (0.1 deg).
constexpr double kMinGravityM_S2 = 5.0;
constexpr double kMaxGravityM_S2 = 15.0;
constexpr double kRealignRad = 0.1 * M_PI / 180.0;

runtime::Qos stream_qos() {
  return runtime::Qos(runtime::QosRole::kOdometry).keep_last(kRosDefaultDepth).volatile_durability();
}

// Like a latched ROS 2 topic (rviz2 "Transient Local"): a late subscriber gets the current path /
// cloud; volatile ROS 2 subscribers still match.
runtime::Qos latched_qos() { return runtime::Qos(runtime::QosRole::kCalibration).keep_last(1).transient_local(1); }

// As tf2_ros's broadcasters (tf2_ros/qos.hpp): /tf is DynamicBroadcasterQoS (reliable, volatile, keep last
// 100), /tf_static StaticBroadcasterQoS (reliable, transient local, keep last 1: one message holding
// every static transform, replayed to late joiners).
constexpr int kTfDepth = 100;
// Frames whose TF waits for the calibration at most (a run's first frames, see on_odometry).
constexpr std::size_t kHeldTfFrames = 100;
runtime::Qos tf_qos() { return runtime::Qos(runtime::QosRole::kOdometry).keep_last(kTfDepth).volatile_durability(); }
runtime::Qos tf_static_qos() { return latched_qos(); }

// tf2 refuses frame ids with a leading '/'; the TF tree needs one name per frame.
void check_frame_names(const Frames& frames) {
  const std::pair<const char*, const std::string*> names[] = {{"world_frame", &frames.world},
                                                              {"camera_frame", &frames.camera},
                                                              {"map_frame", &frames.map},
                                                              {"odom_frame", &frames.odom},
                                                              {"base_frame", &frames.base}};
  for (const auto& [field, name] : names) {
    if (name->empty() || name->front() == '/') {
      throw std::runtime_error(std::string(field) + ": '" + *name +
                               "': expected a tf2 frame id (not empty, no leading '/')");
    }
    for (const auto& [other_field, other] : names) {
      if (field != other_field && *name == *other) {
        throw std::runtime_error(std::string(field) + " and " + other_field + " are both '" + *name +
                                 "': each frame of the TF tree needs its own name (docs/ros2.md, Frames)");
      }
    }
  }
}

bool is_unit_quaternion(const msg::Pose& pose) {
  const double* q = pose.orientation_xyzw;
  const double norm2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  return std::abs(norm2 - 1.0) < kUnitQuaternionTolerance;
}

}  // namespace

BridgeOptions BridgeOptions::from(const runtime::Config& config) {
  BridgeOptions options;
  options.ros_namespace = config.get_string("ros_namespace", options.ros_namespace);
  options.frames.world = config.get_string("world_frame", options.frames.world);
  options.frames.camera = config.get_string("camera_frame", options.frames.camera);
  options.frames.map = config.get_string("map_frame", options.frames.map);
  options.frames.odom = config.get_string("odom_frame", options.frames.odom);
  options.frames.base = config.get_string("base_frame", options.frames.base);
  check_frame_names(options.frames);
  options.publish_period_s =
      config.get_double("publish_period_s", options.publish_period_s, kMinPublishPeriod_s, kMaxPublishPeriod_s);
  if (options.ros_namespace.empty() || options.ros_namespace.front() == '/' || options.ros_namespace.back() == '/') {
    throw std::runtime_error("ros_namespace: '" + options.ros_namespace +
                             "': expected a ROS name without leading or trailing '/' (e.g. heslam, robot1/slam)");
  }
  return options;
}

Ros2Bridge::Ros2Bridge(const runtime::CommonArgs& args) : Component("ros2_bridge", args) {}

std::string Ros2Bridge::help_notes() {
  const BridgeOptions defaults;
  char period[32];
  std::snprintf(period, sizeof period, "%g", defaults.publish_period_s);
  return "\nTopics (heslam, in the --namespace -> ROS 2, NS = ros_namespace; docs/ros2.md):\n"
         "  odometry                -> rt/NS/odometry             nav_msgs/Odometry (each tracked frame)\n"
         "                          -> rt/NS/pose                 geometry_msgs/PoseStamped\n"
         "  map/keyframes + states  -> rt/NS/keyframe_trajectory  nav_msgs/Path (transient local)\n"
         "  map/points              -> rt/NS/map_points           sensor_msgs/PointCloud2 (transient local)\n"
         "  odometry                -> rt/tf                      tf2_msgs/TFMessage: map -> odom -> base_link\n"
         "  camera/calibration      -> rt/tf_static               tf2_msgs/TFMessage: base_link -> camera_frame,\n"
         "                                                        map -> world_frame (transient local)\n"
         "  map/occupancy_grid      -> rt/map                     nav_msgs/OccupancyGrid in map_frame (transient "
         "local)\n"
         "  map/dense_cloud         -> rt/NS/dense_cloud          sensor_msgs/PointCloud2 in map_frame (transient "
         "local)\n"
         "Config fields (--config FILE, all optional):\n"
         "  ros_namespace     ROS 2 namespace of the topics (default " +
         defaults.ros_namespace +
         ")\n"
         "  world_frame       frame_id of poses, path and cloud (default " +
         defaults.frames.world +
         ")\n"
         "  camera_frame      child_frame_id of the odometry, child of base_frame (default " +
         defaults.frames.camera +
         ")\n"
         "  map_frame         REP 105 map: the body at the first keyframe (default " +
         defaults.frames.map +
         ")\n"
         "  odom_frame        REP 105 odom: continuous, without loop corrections (default " +
         defaults.frames.odom +
         ")\n"
         "  base_frame        the body (calibration T_BS; default " +
         defaults.frames.base +
         ")\n"
         "  publish_period_s  how often a changed path / cloud is sent, s (default " +
         period + ")\n";
}

void Ros2Bridge::configure(const runtime::Config& config) {
  options_ = BridgeOptions::from(config);
  const std::string prefix = options_.ros_namespace + "/";
  odometry_writer_.emplace(participant(), &nav_msgs_msg_dds__Odometry__desc, ros2_topic(prefix + "odometry"),
                           stream_qos());
  pose_writer_.emplace(participant(), &geometry_msgs_msg_dds__PoseStamped__desc, ros2_topic(prefix + "pose"),
                       stream_qos());
  path_writer_.emplace(participant(), &nav_msgs_msg_dds__Path__desc, ros2_topic(prefix + "keyframe_trajectory"),
                       latched_qos());
  cloud_writer_.emplace(participant(), &sensor_msgs_msg_dds__PointCloud2__desc, ros2_topic(prefix + "map_points"),
                        latched_qos());
  // /tf and /tf_static are global ROS 2 names (tf2 listens there), not under the namespace.
  tf_writer_.emplace(participant(), &tf2_msgs_msg_dds__TFMessage__desc, ros2_topic("tf"), tf_qos());
  tf_static_writer_.emplace(participant(), &tf2_msgs_msg_dds__TFMessage__desc, ros2_topic("tf_static"),
                            tf_static_qos());

  // /map is a global ROS 2 name (nav2's map_server publishes there), not under the namespace.
  occupancy_grid_writer_.emplace(participant(), &nav_msgs_msg_dds__OccupancyGrid__desc, ros2_topic("map"),
                                 latched_qos());
  dense_cloud_writer_.emplace(participant(), &sensor_msgs_msg_dds__PointCloud2__desc,
                              ros2_topic(prefix + "dense_cloud"), latched_qos());
  subscribe(topics().occupancy_grid(), [this](runtime::Received<msg::OccupancyGrid2D>& received) {
    if (!received.info.valid_data) return;
    const msg::OccupancyGrid2D& grid = *received.sample;
    if (const std::string problem = occupancy::check_grid(grid); !problem.empty()) {
      stats().count("bad_occupancy_grids");
      log().warn_throttled("bad_occupancy_grids", "topic ", topics().occupancy_grid().name, ": ", problem,
                           "; skipped (counted as bad_occupancy_grids)");
      return;
    }
    PendingGrid pending{grid, {}};
    const auto cells = runtime::view(grid.cells);
    pending.cells.assign(cells.begin(), cells.end());
    pending.header.cells = {};
    pending_grid_ = std::move(pending);
    publish_occupancy();
  });
  subscribe(topics().dense_cloud(), [this](runtime::Received<msg::DenseCloud>& received) {
    if (!received.info.valid_data) return;
    const auto xyz = runtime::view(received.sample->xyz_w_m);
    std::vector<std::array<double, 3>> points;
    points.reserve(xyz.size() / 3);
    bool finite = xyz.size() % 3 == 0;
    for (std::size_t i = 0; finite && i + 2 < xyz.size(); i += 3) {
      finite = std::isfinite(xyz[i]) && std::isfinite(xyz[i + 1]) && std::isfinite(xyz[i + 2]);
      points.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
    }
    if (!finite) {
      stats().count("bad_dense_clouds");
      log().warn_throttled("bad_dense_clouds", "topic ", topics().dense_cloud().name, ": field xyz_w_m: ", xyz.size(),
                           " values, not finite x, y, z triples; skipped (counted as bad_dense_clouds)");
      return;
    }
    pending_dense_cloud_.emplace(received.sample->stamp_ns, std::move(points));
    publish_occupancy();
  });
  subscribe(topics().calibration(), [this](runtime::Received<msg::StereoCalibration>& received) {
    if (received.info.valid_data) on_calibration(*received.sample);
  });

  subscribe(topics().odometry(), [this](runtime::Received<msg::Odometry>& received) {
    if (received.info.valid_data) on_odometry(*received.sample);
  });
  subscribe(topics().keyframes(), [this](runtime::Received<msg::Keyframe>& received) {
    if (!received.info.valid_data) return;
    KeyframeEntry& entry = keyframes_[received.sample->id];
    if (!entry.stamp_ns) {
      entry.stamp_ns = received.sample->stamp_ns;
      entry.T_wc = received.sample->T_wc;
    }
    path_changed_ = true;
  });
  subscribe(topics().keyframe_states(), [this](runtime::Received<msg::KeyframeState>& received) {
    if (!received.info.valid_data) return;
    KeyframeEntry& entry = keyframes_[received.sample->id];
    entry.T_wc = received.sample->T_wc;
    entry.culled = received.sample->culled;
    path_changed_ = true;
  });
  subscribe(topics().map_points(), [this](runtime::Received<msg::MapPointState>& received) {
    const msg::MapPointState& point = *received.sample;
    if (!received.info.valid_data || point.culled || point.merged_into != 0) {
      cloud_changed_ = points_w_m_.erase(point.id) > 0 || cloud_changed_;
      return;
    }
    points_w_m_[point.id] = {point.position_w_m[0], point.position_w_m[1], point.position_w_m[2]};
    cloud_changed_ = true;
  });
  log().info("ROS 2 topics: rt/", prefix, "odometry, rt/", prefix, "pose, rt/", prefix, "keyframe_trajectory, rt/",
             prefix, "map_points (frame '", options_.frames.world, "'), rt/tf (", options_.frames.map, " -> ",
             options_.frames.odom, " -> ", options_.frames.base, "), rt/tf_static, rt/map and rt/", prefix,
             "dense_cloud (frame '", options_.frames.map, "')");
}

void Ros2Bridge::on_odometry(const msg::Odometry& odometry) {
  newest_stamp_ns_ = std::max(newest_stamp_ns_, odometry.stamp_ns);
  // A frame that is not tracked carries no pose (the identity): ROS 2 gets nothing for it.
  const std::int64_t state = runtime::wire_value(odometry.state);  // any value may come (runtime/wire_enum.hpp)
  if (state != heslam_msg_TRACKING_OK && state != heslam_msg_TRACKING_INERTIAL_ONLY) {
    stats().count("untracked_frames_skipped");
    return;
  }
  take_gravity(odometry);
  odometry_writer_->write(OdometryMessage(odometry, options_.frames).get());
  pose_writer_->write(PoseStampedMessage(odometry.stamp_ns, odometry.T_wc, options_.frames).get());
  stats().count("odometry_published");
  const TfFrame frame{odometry.stamp_ns, odometry.seq, odometry.T_wc, odometry.T_oc};
  if (!T_B_rect_) {
    // The body frame comes with the calibration. It precedes a run's first frame, but this bridge may
    // discover the frontend's (transient local) odometry before the replay's calibration: hold the frame.
    if (tf_held_.size() == kHeldTfFrames) {
      stats().count("tf_skipped_without_calibration");
      log().warn_throttled("tf_skipped_without_calibration", "frame ", tf_held_.front().seq, ": no calibration on ",
                           topics().calibration().name, " after ", kHeldTfFrames,
                           " frames: no TF for it (the body frame is unknown)");
      tf_held_.pop_front();
    }
    tf_held_.push_back(frame);
    return;
  }
  publish_tf(frame);
}

void Ros2Bridge::publish_tf(const TfFrame& frame) {
  if (!is_unit_quaternion(frame.T_oc)) {
    stats().count("tf_skipped_bad_T_oc");
    log().warn_throttled("tf_skipped_bad_T_oc", "topic ", topics().odometry().name, ": frame ", frame.seq,
                         ": field T_oc has no unit quaternion (not from a heslam frontend of this schema): no TF");
    return;
  }
  const Rep105Transforms tf =
      rep105_transforms(messages::to_pose(frame.T_wc), messages::to_pose(frame.T_oc), *T_B_rect_, T_map_b0());
  tf_writer_->write(TfMessage(frame.stamp_ns, {{options_.frames.map, options_.frames.odom, tf.T_map_odom},
                                               {options_.frames.odom, options_.frames.base, tf.T_odom_base}})
                        .get());
  stats().count("tf_published");
}

void Ros2Bridge::on_calibration(const msg::StereoCalibration& calibration) {
  Pose3 T_B_rect;
  try {
    // The frontend's own rectification of the same calibration, hence its rectified camera exactly.
    T_B_rect = StereoRectifier(messages::to_calibration(calibration)).T_B_rect();
  } catch (const std::exception& error) {
    stats().count("bad_calibrations");
    log().error("topic ", topics().calibration().name, ": ", error.what(), " (no TF until a good one arrives)");
    return;
  }
  T_B_rect_ = T_B_rect;
  publish_static_tf();
  if (!tf_held_.empty()) {
    log().info("calibration on ", topics().calibration().name, ": the TF of ", tf_held_.size(),
               " frame(s) tracked before it goes out now");
    for (const TfFrame& frame : tf_held_) publish_tf(frame);
    tf_held_.clear();
  }
  publish_occupancy();
}

void Ros2Bridge::publish_static_tf() {
  if (!T_B_rect_) return;
  // One message with every static transform, as tf2_ros's StaticTransformBroadcaster sends it.
  tf_static_writer_->write(
      TfMessage(0, {{options_.frames.base, options_.frames.camera, base_to_camera(*T_B_rect_)},
                    {options_.frames.map, options_.frames.world, map_to_world(*T_B_rect_, T_map_b0())}})
          .get());
  stats().count("tf_static_published");
}

Pose3 Ros2Bridge::T_map_b0() const {
  return gravity_w_ && T_B_rect_ ? gravity_aligned_map(*gravity_w_, *T_B_rect_) : Pose3::Identity();
}

void Ros2Bridge::take_gravity(const msg::Odometry& odometry) {
  if (!odometry.gravity_valid) return;
  const Eigen::Vector3d g_w(odometry.g_w[0], odometry.g_w[1], odometry.g_w[2]);
  if (!g_w.allFinite() || !(g_w.norm() > kMinGravityM_S2 && g_w.norm() < kMaxGravityM_S2)) {
    stats().count("bad_gravities");
    log().warn_throttled("bad_gravities", "topic ", topics().odometry().name, ": frame ", odometry.seq,
                         ": field g_w is not a gravity (finite, ", kMinGravityM_S2, "..", kMaxGravityM_S2,
                         " m/s^2): map keeps its alignment");
    return;
  }
  // The initialization's gravity is refined for a while after it: map turns with it only when it moved
  // noticeably, so tf_static is sent again a few times, not at every frame.
  if (gravity_w_ && std::acos(std::clamp(gravity_w_->normalized().dot(g_w.normalized()), -1.0, 1.0)) < kRealignRad) {
    return;
  }
  if (!gravity_w_) log().info("inertial run: map is gravity-aligned from frame ", odometry.seq, " on (z up)");
  gravity_w_ = g_w;
  stats().count("map_alignments");
  publish_static_tf();
}

void Ros2Bridge::publish_occupancy() {
  if (!T_B_rect_) {
    if (pending_grid_ || pending_dense_cloud_) stats().count("occupancy_waiting_for_calibration");
    return;  // the map frame comes with the calibration (transient local): published when it arrives
  }
  const Pose3 T_map_world = map_to_world(*T_B_rect_, T_map_b0());
  if (pending_grid_) {
    msg::OccupancyGrid2D grid = pending_grid_->header;
    runtime::borrow(grid.cells, pending_grid_->cells);
    occupancy_grid_writer_->write(OccupancyGridMessage(grid, T_map_world, options_.frames).get());
    stats().count("occupancy_grids_published");
    pending_grid_.reset();
  }
  if (pending_dense_cloud_) {
    std::vector<std::array<double, 3>>& points = pending_dense_cloud_->second;
    for (auto& p : points) {
      const Eigen::Vector3d m = T_map_world * Eigen::Vector3d(p[0], p[1], p[2]);
      p = {m.x(), m.y(), m.z()};
    }
    dense_cloud_writer_->write(PointCloudMessage(pending_dense_cloud_->first, points, options_.frames.map).get());
    stats().count("dense_clouds_published");
    pending_dense_cloud_.reset();
  }
}

void Ros2Bridge::publish_map_if_changed() {
  if (path_changed_) {
    std::vector<KeyframePose> keyframes;
    for (const auto& [id, entry] : keyframes_) {
      if (entry.stamp_ns && !entry.culled) keyframes.push_back({*entry.stamp_ns, entry.T_wc});
    }
    path_writer_->write(PathMessage(std::move(keyframes), options_.frames).get());
    stats().count("paths_published");
    path_changed_ = false;
  }
  if (cloud_changed_) {
    std::vector<std::array<double, 3>> points;
    points.reserve(points_w_m_.size());
    for (const auto& [id, position] : points_w_m_) points.push_back(position);
    cloud_writer_->write(PointCloudMessage(newest_stamp_ns_, points, options_.frames).get());
    stats().count("point_clouds_published");
    cloud_changed_ = false;
  }
}

void Ros2Bridge::run() {
  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.publish_period_s));
  auto next_publish = std::chrono::steady_clock::now() + period;
  while (spin_once(std::chrono::milliseconds(50))) {
    if (std::chrono::steady_clock::now() < next_publish) continue;
    next_publish += period;
    publish_map_if_changed();
  }
  publish_map_if_changed();
}

}  // namespace heslam::ros2
