// heslam-ros2-bridge: the ROS 2 type names exactly as ROS 2 names them on DDS, the conversions on
// known values, and the real bridge process republishing odometry, the keyframe path and map points
// to a subscriber that uses only the ROS 2 types and topic names (as a ROS 2 node would; ROS 2 itself
// is not installable here).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

#include <dds/ddsi/ddsi_serdata.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "child_process.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/map/ids.hpp"
#include "runtime/participant.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "test_support.hpp"
#include "tiny_euroc_sensor.hpp"
#include "tools/replay/replay_messages.hpp"
#include "tools/ros2_bridge/ros2_conversions.hpp"
#include "tools/ros2_bridge/tf_tree.hpp"

namespace heslam::ros2 {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

// rosidl's DDS names: <package>::msg::dds_::<Message>_ (what rmw_cyclonedds_cpp registers).
TEST(Ros2Types, TypeNamesAreRos2s) {
  EXPECT_STREQ(builtin_interfaces_msg_dds__Time__desc.m_typename, "builtin_interfaces::msg::dds_::Time_");
  EXPECT_STREQ(std_msgs_msg_dds__Header__desc.m_typename, "std_msgs::msg::dds_::Header_");
  EXPECT_STREQ(geometry_msgs_msg_dds__PoseStamped__desc.m_typename, "geometry_msgs::msg::dds_::PoseStamped_");
  EXPECT_STREQ(nav_msgs_msg_dds__Odometry__desc.m_typename, "nav_msgs::msg::dds_::Odometry_");
  EXPECT_STREQ(nav_msgs_msg_dds__Path__desc.m_typename, "nav_msgs::msg::dds_::Path_");
  EXPECT_STREQ(sensor_msgs_msg_dds__PointCloud2__desc.m_typename, "sensor_msgs::msg::dds_::PointCloud2_");
  EXPECT_STREQ(geometry_msgs_msg_dds__TransformStamped__desc.m_typename, "geometry_msgs::msg::dds_::TransformStamped_");
  EXPECT_STREQ(tf2_msgs_msg_dds__TFMessage__desc.m_typename, "tf2_msgs::msg::dds_::TFMessage_");
  EXPECT_EQ(ros2_topic("heslam/odometry"), "rt/heslam/odometry");
  // Field layout: sizes of the fixed parts as the ROS 2 definitions give them.
  EXPECT_EQ(sizeof(Odometry{}.pose.covariance) / sizeof(double), 36u);
  EXPECT_EQ(sizeof(Odometry{}.twist.covariance) / sizeof(double), 36u);
}

TEST(Ros2Conversions, TimeSplitsNanosecondsLikeRos2) {
  const Time t = to_time(1403636584763555584);
  EXPECT_EQ(t.sec, 1403636584);
  EXPECT_EQ(t.nanosec, 763555584u);
  const Time negative = to_time(-1);
  EXPECT_EQ(negative.sec, -1);
  EXPECT_EQ(negative.nanosec, 999999999u);
}

msg::Pose test_pose(double x) {
  msg::Pose pose{};
  pose.position_m[0] = x;
  pose.position_m[1] = -2.0;
  pose.position_m[2] = 0.5;
  pose.orientation_xyzw[2] = std::sqrt(0.5);
  pose.orientation_xyzw[3] = std::sqrt(0.5);
  return pose;
}

Pose3 pose3(double angle_rad, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

double pose_difference(const Pose3& a, const Pose3& b) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff(); }

// map -> odom -> base_link composes to the body pose of the recorder (T_B_rect T_wc T_B_rect^-1), and a
// loop correction (a jump of T_wc with the same T_oc) moves map -> odom only.
TEST(Ros2Tf, Rep105TransformsComposeToTheBodyPoseAndCorrectionsStayInMapToOdom) {
  const Pose3 T_B_rect = pose3(1.6, {0.2, -1.0, 0.3}, {-0.02, 0.07, 0.01});
  const Pose3 T_oc = pose3(0.4, {0.0, 1.0, 0.1}, {1.0, 0.2, 3.0});
  const Pose3 correction = pose3(0.05, {0.0, 1.0, 0.0}, {0.3, 0.0, -0.1});
  for (const Pose3& T_wo : {Pose3(Pose3::Identity()), correction}) {
    const Pose3 T_wc = T_wo * T_oc;
    const Rep105Transforms tf = rep105_transforms(T_wc, T_oc, T_B_rect);
    EXPECT_LT(pose_difference(tf.T_map_odom * tf.T_odom_base, T_B_rect * T_wc * T_B_rect.inverse()), 1e-12);
    EXPECT_LT(pose_difference(tf.T_odom_base, T_B_rect * T_oc * T_B_rect.inverse()), 1e-12);
    // base_link -> camera on /tf_static closes the chain to the tracked camera in map (= world moved by T_B_rect).
    EXPECT_LT(pose_difference(tf.T_map_odom * tf.T_odom_base * base_to_camera(T_B_rect), map_to_world(T_B_rect) * T_wc),
              1e-12);
  }
  EXPECT_LT(pose_difference(rep105_transforms(T_oc, T_oc, T_B_rect).T_map_odom, Pose3::Identity()), 1e-12);
}

// Inertial runs: with gravity from the odometry, map is z up (gravity along -z of map) with the origin and
// heading of the body at the first keyframe, and the chain map -> odom -> base_link -> camera still
// equals map -> heslam_world times the tracked pose; odom -> base_link is not changed by it.
TEST(Ros2Tf, GravityAlignedMapIsZUpAndKeepsTheChainAndTheHeading) {
  const Pose3 T_B_rect = pose3(1.6, {0.2, -1.0, 0.3}, {-0.02, 0.07, 0.01});
  // The world (rectified camera at the first keyframe) is tilted: gravity in it is not along an axis.
  const Pose3 T_true_w = pose3(0.3, {1.0, 0.4, -0.2}, {0.0, 0.0, 0.0});  // world -> a z-up frame
  const Eigen::Vector3d g_w = T_true_w.linear().transpose() * Eigen::Vector3d(0.0, 0.0, -9.81);
  const Pose3 T_map_b0 = gravity_aligned_map(g_w, T_B_rect);
  EXPECT_LT(T_map_b0.translation().norm(), 1e-15);  // the same origin
  const Eigen::Vector3d g_map = map_to_world(T_B_rect, T_map_b0).linear() * g_w;
  EXPECT_LT((g_map.normalized() - Eigen::Vector3d(0.0, 0.0, -1.0)).norm(), 1e-12);
  // The smallest rotation: its axis is horizontal in map (no rotation about the vertical added).
  const Eigen::AngleAxisd turn(T_map_b0.linear());
  EXPECT_LT(std::abs(turn.axis().z()) * std::sin(turn.angle()), 1e-12);
  const Pose3 T_oc = pose3(0.4, {0.0, 1.0, 0.1}, {1.0, 0.2, 3.0});
  const Pose3 T_wc = pose3(0.02, {0.0, 0.0, 1.0}, {0.1, 0.0, 0.0}) * T_oc;
  const Rep105Transforms tf = rep105_transforms(T_wc, T_oc, T_B_rect, T_map_b0);
  EXPECT_LT(pose_difference(tf.T_map_odom * tf.T_odom_base * base_to_camera(T_B_rect),
                            map_to_world(T_B_rect, T_map_b0) * T_wc),
            1e-12);
  EXPECT_LT(pose_difference(tf.T_odom_base, rep105_transforms(T_wc, T_oc, T_B_rect).T_odom_base), 1e-15);
  EXPECT_THROW(gravity_aligned_map(Eigen::Vector3d::Zero(), T_B_rect), std::invalid_argument);
}

TEST(Ros2Tf, TfMessageNamesParentAndChildAndCarriesTheTransform) {
  const Frames frames;
  const Pose3 T = pose3(0.3, {1.0, 0.0, 0.0}, {1.0, 2.0, 3.0});
  const TfMessage message(1'500'000'000, {{frames.map, frames.odom, T}, {frames.odom, frames.base, T.inverse()}});
  const TFMessage& tf = message.get();
  ASSERT_EQ(tf.transforms._length, 2u);
  const TransformStamped& first = tf.transforms._buffer[0];
  EXPECT_EQ(std::string(first.header.frame_id), "map");
  EXPECT_EQ(std::string(first.child_frame_id), "odom");
  EXPECT_EQ(first.header.stamp.sec, 1);
  EXPECT_EQ(first.header.stamp.nanosec, 500000000u);
  EXPECT_DOUBLE_EQ(first.transform.translation.z, 3.0);
  EXPECT_NEAR(first.transform.rotation.x, std::sin(0.15), 1e-12);
  EXPECT_NEAR(first.transform.rotation.w, std::cos(0.15), 1e-12);
  EXPECT_EQ(std::string(tf.transforms._buffer[1].header.frame_id), "odom");
  EXPECT_EQ(std::string(tf.transforms._buffer[1].child_frame_id), "base_link");
}

// heslam's T_wc_covariance (upper triangle over rotation x y z, position x y z) -> ROS 2's full 6x6 over
// x y z, rotation x y z: entry (i, j) of heslam's matrix is 10 i + j, so each ROS 2 entry names its source.
TEST(Ros2Conversions, CovarianceIsReorderedToRos2sPositionFirstAndMirrored) {
  double upper[21];
  int k = 0;
  for (int row = 0; row < 6; ++row) {
    for (int col = row; col < 6; ++col) upper[k++] = 10.0 * row + col;
  }
  const std::array<double, 36> ros = ros_pose_covariance(upper);
  const int heslam_index[6] = {3, 4, 5, 0, 1, 2};
  for (int row = 0; row < 6; ++row) {
    for (int col = 0; col < 6; ++col) {
      const int a = std::min(heslam_index[row], heslam_index[col]), b = std::max(heslam_index[row], heslam_index[col]);
      EXPECT_EQ(ros[static_cast<std::size_t>(6 * row + col)], 10.0 * a + b) << row << ", " << col;
    }
  }
  EXPECT_EQ(ros[0], 33.0);  // var(x) = heslam's position x variance
  EXPECT_EQ(ros[21], 0.0);  // var(rotation about X) = heslam's (0, 0)
  EXPECT_EQ(ros[3], 3.0);   // cov(x, rotation about X)
}

TEST(Ros2Conversions, OdometryPathAndCloudCarryTheValues) {
  const Frames frames;
  msg::Odometry odometry{};
  odometry.stamp_ns = 2'500'000'001;
  odometry.state = heslam_msg_TRACKING_OK;
  odometry.T_wc = test_pose(1.25);
  const OdometryMessage ros_odometry(odometry, frames);
  EXPECT_EQ(ros_odometry.get().header.stamp.sec, 2);
  EXPECT_EQ(ros_odometry.get().header.stamp.nanosec, 500000001u);
  EXPECT_STREQ(ros_odometry.get().header.frame_id, "heslam_world");
  EXPECT_STREQ(ros_odometry.get().child_frame_id, "heslam_camera");
  EXPECT_EQ(ros_odometry.get().pose.pose.position.x, 1.25);
  EXPECT_EQ(ros_odometry.get().pose.pose.orientation.w, std::sqrt(0.5));

  const PathMessage path({{300, test_pose(3.0)}, {100, test_pose(1.0)}, {200, test_pose(2.0)}}, frames);
  ASSERT_EQ(path.get().poses._length, 3u);
  EXPECT_EQ(path.get().poses._buffer[0].pose.position.x, 1.0);  // stamp order
  EXPECT_EQ(path.get().poses._buffer[2].header.stamp.nanosec, 300u);
  EXPECT_EQ(path.get().header.stamp.nanosec, 300u);

  const PointCloudMessage cloud(7, {{1.0, 2.0, 3.0}, {-4.0, 0.5, 8.0}}, frames);
  const PointCloud2& c = cloud.get();
  EXPECT_EQ(c.height, 1u);
  EXPECT_EQ(c.width, 2u);
  EXPECT_EQ(c.point_step, 12u);
  EXPECT_EQ(c.row_step, 24u);
  ASSERT_EQ(c.fields._length, 3u);
  EXPECT_STREQ(c.fields._buffer[1].name, "y");
  EXPECT_EQ(c.fields._buffer[1].offset, 4u);
  EXPECT_EQ(c.fields._buffer[1].datatype, 7);  // FLOAT32
  EXPECT_EQ(c.fields._buffer[1].count, 1u);
  ASSERT_EQ(c.data._length, 24u);
  float second[3];
  std::memcpy(second, c.data._buffer + 12, sizeof second);
  EXPECT_EQ(second[0], -4.0f);
  EXPECT_EQ(second[2], 8.0f);
  EXPECT_FALSE(c.is_bigendian);
  EXPECT_TRUE(c.is_dense);
}

// A subscriber that knows only the ROS 2 type and topic name, like a ROS 2 node.
template <typename T>
class Ros2Subscriber {
 public:
  // latched: transient local, to get the path / cloud sent before joining (as rviz2's "Transient
  // Local"); else rclcpp's default profile (reliable, volatile, keep last 10).
  Ros2Subscriber(const runtime::Participant& participant, const dds_topic_descriptor_t* descriptor,
                 const std::string& topic, bool latched)
      : descriptor_(descriptor) {
    topic_ = runtime::Entity(dds_create_topic(participant.handle(), descriptor, topic.c_str(), nullptr, nullptr));
    runtime::Qos qos = runtime::Qos(runtime::QosRole::kOdometry).keep_last(10).volatile_durability();
    if (latched) qos.transient_local(1);
    reader_ = runtime::Entity(dds_create_reader(participant.handle(), topic_.get(), qos.get(), nullptr));
  }

  bool matched() const {
    dds_subscription_matched_status_t status{};
    return dds_get_subscription_matched_status(reader_.get(), &status) == DDS_RETCODE_OK && status.current_count > 0;
  }

  // Takes samples until one is accepted by `accept` (which sees it while it is alive) or the timeout.
  template <typename Accept>
  bool wait_for(Accept accept, seconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {  // at least one take, also with a zero timeout
      void* sample = dds_alloc(descriptor_->m_size);
      dds_sample_info_t info{};
      void* buffer[1] = {sample};
      const dds_return_t n = dds_take(reader_.get(), buffer, &info, 1, 1);
      const bool accepted = n > 0 && info.valid_data && accept(*static_cast<const T*>(sample));
      dds_sample_free(sample, descriptor_, DDS_FREE_ALL);
      if (accepted) return true;
      if (n > 0) continue;
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(milliseconds(20));
    }
  }

 private:
  const dds_topic_descriptor_t* descriptor_;
  runtime::Entity topic_;
  runtime::Entity reader_;
};

// The first 4 bytes of the next serialized sample on a topic (the CDR encapsulation header), read
// without deserializing; empty on timeout.
std::vector<unsigned char> encapsulation_header(const runtime::Participant& participant,
                                                const dds_topic_descriptor_t* descriptor, const std::string& topic,
                                                seconds timeout) {
  runtime::Entity topic_entity(dds_create_topic(participant.handle(), descriptor, topic.c_str(), nullptr, nullptr));
  const runtime::Qos qos = runtime::Qos(runtime::QosRole::kCalibration).keep_last(1).transient_local(1);
  runtime::Entity reader(dds_create_reader(participant.handle(), topic_entity.get(), qos.get(), nullptr));
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    ddsi_serdata* serdata = nullptr;
    dds_sample_info_t info{};
    if (dds_takecdr(reader.get(), &serdata, 1, &info, DDS_ANY_STATE) > 0) {
      std::vector<unsigned char> header(4);
      ddsi_serdata_to_ser(serdata, 0, header.size(), header.data());
      ddsi_serdata_unref(serdata);
      if (info.valid_data) return header;
    }
    std::this_thread::sleep_for(milliseconds(20));
  }
  return {};
}

// --help lists what the bridge reads and writes and its config fields, not only the common flags.
TEST(Ros2BridgeProcess, HelpListsTopicsAndConfigFields) {
  const test::ScratchDir dir("ros2_bridge_help");
  test::ChildProcess help(test::bin_dir() / "heslam-ros2-bridge", {"--help"}, dir.path(), "bridge_help");
  ASSERT_EQ(help.wait(seconds(30)), 0) << help.err();
  const std::string text = help.out();
  EXPECT_NE(text.find("--domain"), std::string::npos) << text;  // the common flags still come first
  for (const char* line :
       {"  odometry                -> rt/NS/odometry             nav_msgs/Odometry (each tracked frame)\n",
        "                          -> rt/NS/pose                 geometry_msgs/PoseStamped\n",
        "  map/keyframes + states  -> rt/NS/keyframe_trajectory  nav_msgs/Path (transient local)\n",
        "  map/points              -> rt/NS/map_points           sensor_msgs/PointCloud2 (transient local)\n",
        "  ros_namespace     ROS 2 namespace of the topics (default heslam)\n",
        "  world_frame       frame_id of poses, path and cloud (default heslam_world)\n",
        "  camera_frame      child_frame_id of the odometry, child of base_frame (default heslam_camera)\n",
        "  map_frame         REP 105 map: the body at the first keyframe (default map)\n",
        "  odom_frame        REP 105 odom: continuous, without loop corrections (default odom)\n",
        "  base_frame        the body (calibration T_BS; default base_link)\n",
        "  odometry                -> rt/tf                      tf2_msgs/TFMessage: map -> odom -> base_link\n",
        "  publish_period_s  how often a changed path / cloud is sent, s (default 1)\n"}) {
    EXPECT_NE(text.find(line), std::string::npos) << "missing: " << line << "in:\n" << text;
  }
}

// heslam's world (the first rectified camera) is a child of map (the body at the first keyframe): one
// name for both would make the TF tree lie, so it is refused with a line naming the fields.
TEST(Ros2BridgeProcess, RefusesOneNameForTwoFrames) {
  const test::ScratchDir dir("ros2_bridge_frames");
  std::ofstream(dir.path() / "bridge.yaml") << "world_frame: map\n";
  test::ChildProcess bridge(
      test::bin_dir() / "heslam-ros2-bridge",
      {"--domain", std::to_string(test::exclusive_domain_id()), "--config", (dir.path() / "bridge.yaml").string()},
      dir.path(), "bridge_frames");
  EXPECT_NE(bridge.wait(seconds(30)).value_or(0), 0);
  EXPECT_NE(bridge.err().find("world_frame and map_frame are both 'map'"), std::string::npos) << bridge.err();
}

TEST(Ros2BridgeProcess, RepublishesOdometryPathAndPointsOnRos2Topics) {
  const test::ScratchDir dir("ros2_bridge");
  const int domain = test::exclusive_domain_id();
  runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  const runtime::Topics topics;
  runtime::Writer<msg::Odometry> odometry(participant, topics.odometry());
  runtime::Writer<msg::Keyframe> keyframes(participant, topics.keyframes());
  runtime::Writer<msg::KeyframeState> states(participant, topics.keyframe_states());
  runtime::Writer<msg::MapPointState> points(participant, topics.map_points());
  Ros2Subscriber<Odometry> ros_odometry(participant, &nav_msgs_msg_dds__Odometry__desc, "rt/heslam/odometry", false);
  Ros2Subscriber<PoseStamped> ros_pose(participant, &geometry_msgs_msg_dds__PoseStamped__desc, "rt/heslam/pose", false);
  Ros2Subscriber<Path> ros_path(participant, &nav_msgs_msg_dds__Path__desc, "rt/heslam/keyframe_trajectory", true);
  Ros2Subscriber<PointCloud2> ros_cloud(participant, &sensor_msgs_msg_dds__PointCloud2__desc, "rt/heslam/map_points",
                                        true);

  std::ofstream(dir.path() / "bridge.yaml") << "publish_period_s: 0.2\nworld_frame: slam_world\n";
  test::ChildProcess bridge(test::bin_dir() / "heslam-ros2-bridge",
                            {"--domain", std::to_string(domain), "--config", (dir.path() / "bridge.yaml").string()},
                            dir.path(), "bridge");
  ASSERT_TRUE(odometry.wait_for_readers(1, seconds(20))) << bridge.err();
  ASSERT_TRUE(points.wait_for_readers(1, seconds(20))) << bridge.err();

  // Two keyframes (the second refined by a state, the first's state culls nothing), three points of
  // which one is culled, and a tracked frame.
  for (std::uint64_t id : {1ULL, 2ULL}) {
    msg::Keyframe keyframe{};
    keyframe.id = make_id(kFrontendTag, id);
    keyframe.stamp_ns = 1'000'000'000LL * static_cast<std::int64_t>(id);
    keyframe.T_wc = test_pose(static_cast<double>(id));
    keyframes.write(keyframe);
  }
  msg::KeyframeState refined{};
  refined.id = make_id(kFrontendTag, 2);
  refined.T_wc = test_pose(2.5);
  states.write(refined);
  for (std::uint64_t id : {1ULL, 2ULL, 3ULL}) {
    msg::MapPointState point{};
    point.id = id;
    point.position_w_m[0] = static_cast<double>(id);
    point.position_w_m[1] = 10.0;
    point.culled = id == 3;
    points.write(point);
  }
  msg::Odometry frame{};
  frame.stamp_ns = 2'000'000'123;
  frame.state = heslam_msg_TRACKING_OK;
  frame.T_wc = test_pose(4.0);
  // Repeated until seen: the bridge's ROS 2 writers match our subscribers asynchronously.
  bool odometry_seen = false;
  for (int attempt = 0; attempt < 100 && !odometry_seen; ++attempt) {
    odometry.write(frame);
    odometry_seen = ros_odometry.wait_for(
        [](const Odometry& o) {
          return o.header.stamp.sec == 2 && o.header.stamp.nanosec == 123u && o.pose.pose.position.x == 4.0 &&
                 std::string(o.header.frame_id) == "slam_world" && std::string(o.child_frame_id) == "heslam_camera";
        },
        seconds(0));
    if (!odometry_seen) std::this_thread::sleep_for(milliseconds(100));
  }
  EXPECT_TRUE(odometry_seen) << bridge.err();
  EXPECT_TRUE(ros_pose.wait_for([](const PoseStamped& p) { return p.pose.position.x == 4.0; }, seconds(5)));
  EXPECT_TRUE(ros_path.wait_for(
      [](const Path& path) {
        return path.poses._length == 2 && path.poses._buffer[0].pose.position.x == 1.0 &&
               path.poses._buffer[1].pose.position.x == 2.5 && path.poses._buffer[1].header.stamp.sec == 2;
      },
      seconds(10)))
      << bridge.err();
  EXPECT_TRUE(ros_cloud.wait_for(
      [](const PointCloud2& cloud) {
        if (cloud.width != 2 || cloud.data._length != 24) return false;
        float first[3];
        std::memcpy(first, cloud.data._buffer, sizeof first);
        return first[0] == 1.0f && first[1] == 10.0f && std::string(cloud.header.frame_id) == "slam_world";
      },
      seconds(10)))
      << bridge.err();
  // rmw_cyclonedds_cpp sends and expects plain CDR (XCDR1), little-endian: encapsulation 00 01.
  const std::vector<unsigned char> header =
      encapsulation_header(participant, &nav_msgs_msg_dds__Path__desc, "rt/heslam/keyframe_trajectory", seconds(10));
  ASSERT_EQ(header.size(), 4u);
  EXPECT_EQ(header[0], 0x00);
  EXPECT_EQ(header[1], 0x01) << "CDR_LE (XCDR1) expected, got XCDR2 or big-endian";
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait(seconds(20)).value_or(-1), 0) << bridge.err();
}

// A frame tracked before the bridge has the calibration (discovery may bring the frontend's odometry
// first): its TF is held and goes out when the calibration arrives, not dropped.
TEST(Ros2BridgeProcess, TfOfAFrameTrackedBeforeTheCalibrationGoesOutWhenItArrives) {
  const test::ScratchDir dir("ros2_bridge_tf_held");
  for (const auto& [camera, tx_m] : {std::pair{"cam0", 0.0}, std::pair{"cam1", 0.1}}) {
    fs::create_directories(dir.path() / "mav0" / camera);
    std::ofstream(dir.path() / "mav0" / camera / "sensor.yaml") << test::tiny_euroc_sensor_yaml(tx_m);
  }
  const StereoCalibration calibration = load_euroc_calibration(dir.path() / "mav0");
  const CalibrationMessage calibration_message(calibration, StereoRectifier(calibration).camera());

  const int domain = test::exclusive_domain_id();
  runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  const runtime::Topics topics;
  runtime::Writer<msg::Odometry> odometry(participant, topics.odometry());
  Ros2Subscriber<Odometry> ros_odometry(participant, &nav_msgs_msg_dds__Odometry__desc, "rt/heslam/odometry", false);
  Ros2Subscriber<TFMessage> tf(participant, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf", false);
  test::ChildProcess bridge(test::bin_dir() / "heslam-ros2-bridge", {"--domain", std::to_string(domain)}, dir.path(),
                            "bridge");
  ASSERT_TRUE(odometry.wait_for_readers(1, seconds(20))) << bridge.err();
  const auto match_deadline = std::chrono::steady_clock::now() + seconds(20);
  while (!(tf.matched() && ros_odometry.matched()) && std::chrono::steady_clock::now() < match_deadline) {
    std::this_thread::sleep_for(milliseconds(20));
  }
  ASSERT_TRUE(tf.matched() && ros_odometry.matched()) << bridge.err();

  msg::Odometry frame{};
  frame.stamp_ns = 3'000'000'007;
  frame.state = heslam_msg_TRACKING_OK;
  frame.T_wc = test_pose(4.0);
  frame.T_oc = test_pose(4.0);
  odometry.write(frame);
  // The bridge has taken the frame (its odometry is republished at once) before any calibration exists.
  ASSERT_TRUE(ros_odometry.wait_for([](const Odometry& o) { return o.header.stamp.sec == 3; }, seconds(20)))
      << bridge.err();
  EXPECT_FALSE(tf.wait_for([](const TFMessage&) { return true; }, seconds(0)));

  runtime::Writer<msg::StereoCalibration> calibration_writer(participant, topics.calibration());
  calibration_writer.write(calibration_message.get());
  EXPECT_TRUE(tf.wait_for(
      [](const TFMessage& message) {
        if (message.transforms._length != 2) return false;
        const TransformStamped& odom_base = message.transforms._buffer[1];
        return odom_base.header.stamp.sec == 3 && odom_base.header.stamp.nanosec == 7u &&
               std::string(odom_base.header.frame_id) == "odom" && std::string(odom_base.child_frame_id) == "base_link";
      },
      seconds(20)))
      << bridge.err();
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait(seconds(20)).value_or(-1), 0) << bridge.err();
  EXPECT_NE(bridge.err().find("the TF of 1 frame(s) tracked before it goes out now"), std::string::npos)
      << bridge.err();
}

}  // namespace
}  // namespace heslam::ros2
