// heslam-ros2-bridge's TF (REP 105) on a real run: the full synthetic system (frontend, local mapper,
// loop closer) on corridor_loop, which closes a loop, with the bridge beside it and a subscriber that
// knows only the ROS 2 types and topic names (rt/tf, rt/tf_static). At every tracked frame
// map -> odom -> base_link (-> camera on /tf_static) composes to the frontend's published pose; across
// the loop correction odom -> base_link moves like the camera does, the correction goes into map -> odom.
// The same run is heslam-loop-closer-proximity's corridor loop test: every frame in the trajectory, at
// least one loop accepted, ATE below 0.2 % of the path (the bar of tests/loop_closer/loop_closer_e2e_test.cpp,
// whose bag-of-words runs are there; one 960-frame run instead of two with the same arguments).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <map>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "components/messages/pose.hpp"
#include "pipeline_runs.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/topics.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"
#include "tools/ros2_bridge/ros2_messages.hpp"

namespace heslam::ros2 {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

// As tests/loop_closer: one round of the ring and past its start, so the loop closes.
constexpr int kCorridorFrames = 960;
// The composition is exact arithmetic on doubles sent as doubles: only rounding separates them.
constexpr double kComposeTolerance = 1e-6;
// The issue's bar for a closed loop (as tests/loop_closer): ATE after closing at most 0.2 % of the path length.
constexpr double kMaxAteOfPath = 0.002;

// The sum of "A loops accepted" over the loop closer's summaries (one per process start).
int loops_accepted(const std::string& output) {
  static const std::regex summary(R"((\d+) loops accepted)");
  int total = 0;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), summary); it != std::sregex_iterator(); ++it) {
    total += std::stoi((*it)[1]);
  }
  return total;
}

Pose3 to_pose3(const Transform& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::Quaterniond(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z).toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return T;
}

std::int64_t stamp_ns(const Time& t) { return std::int64_t{t.sec} * 1'000'000'000 + t.nanosec; }

double max_abs_difference(const Pose3& a, const Pose3& b) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff(); }

// A KEEP_ALL reader of one ROS 2 type; each sample is handed to `use` while alive.
template <typename T>
class KeepAllReader {
 public:
  KeepAllReader(const runtime::Participant& participant, const dds_topic_descriptor_t* descriptor,
                const std::string& topic, bool transient_local)
      : descriptor_(descriptor) {
    topic_ = runtime::Entity(dds_create_topic(participant.handle(), descriptor, topic.c_str(), nullptr, nullptr));
    runtime::Qos qos = runtime::Qos(runtime::QosRole::kOdometry).keep_all().volatile_durability();
    if (transient_local) qos.transient_local(1);
    reader_ = runtime::Entity(dds_create_reader(participant.handle(), topic_.get(), qos.get(), nullptr));
  }

  template <typename Use>
  void take_all(Use use) {
    for (;;) {
      void* sample = dds_alloc(descriptor_->m_size);
      dds_sample_info_t info{};
      void* buffer[1] = {sample};
      const dds_return_t n = dds_take(reader_.get(), buffer, &info, 1, 1);
      if (n > 0 && info.valid_data) use(*static_cast<const T*>(sample));
      dds_sample_free(sample, descriptor_, DDS_FREE_ALL);
      if (n <= 0) return;
    }
  }

  bool matched() const {
    dds_subscription_matched_status_t status{};
    return dds_get_subscription_matched_status(reader_.get(), &status) == DDS_RETCODE_OK && status.current_count > 0;
  }

 private:
  const dds_topic_descriptor_t* descriptor_;
  runtime::Entity topic_;
  runtime::Entity reader_;
};

struct FrameTf {
  std::optional<Pose3> T_map_odom;
  std::optional<Pose3> T_odom_base;
};

TEST(Ros2TfEndToEnd, CorridorLoopTfComposesToThePosesAndOdomNeverJumps) {
  fs::path dataset;
  const std::string render_error = test::cached_synth("corridor_loop", kCorridorFrames, dataset);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("ros2_tf_corridor");
  const int domain = test::exclusive_domain_id();
  runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  const runtime::Topics topics;
  runtime::Reader<msg::Odometry> odometry_reader(participant, topics.odometry());
  KeepAllReader<TFMessage> tf_reader(participant, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf", false);
  KeepAllReader<TFMessage> tf_static_reader(participant, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static", true);

  test::ChildProcess bridge(test::bin_dir() / "heslam-ros2-bridge", {"--domain", std::to_string(domain)}, dir.path(),
                            "bridge");
  const auto match_deadline = std::chrono::steady_clock::now() + seconds(30);
  while (!tf_reader.matched() && std::chrono::steady_clock::now() < match_deadline) {
    std::this_thread::sleep_for(milliseconds(50));
  }
  ASSERT_TRUE(tf_reader.matched()) << bridge.err();

  std::map<std::int64_t, FrameTf> tf_by_stamp;
  std::optional<Pose3> T_base_camera;
  std::optional<Pose3> T_map_world;
  std::map<std::int64_t, msg::Odometry> odometry_by_stamp;
  const auto drain = [&] {
    tf_reader.take_all([&](const TFMessage& message) {
      for (std::uint32_t i = 0; i < message.transforms._length; ++i) {
        const TransformStamped& t = message.transforms._buffer[i];
        const std::string parent = t.header.frame_id, child = t.child_frame_id;
        FrameTf& frame = tf_by_stamp[stamp_ns(t.header.stamp)];
        if (parent == "map" && child == "odom") frame.T_map_odom = to_pose3(t.transform);
        if (parent == "odom" && child == "base_link") frame.T_odom_base = to_pose3(t.transform);
      }
    });
    tf_static_reader.take_all([&](const TFMessage& message) {
      for (std::uint32_t i = 0; i < message.transforms._length; ++i) {
        const TransformStamped& t = message.transforms._buffer[i];
        const std::string parent = t.header.frame_id, child = t.child_frame_id;
        if (parent == "base_link" && child == "heslam_camera") T_base_camera = to_pose3(t.transform);
        if (parent == "map" && child == "heslam_world") T_map_world = to_pose3(t.transform);
      }
    });
    for (auto& received : odometry_reader.take()) {
      if (received.info.valid_data) odometry_by_stamp[received.sample->stamp_ns] = *received.sample;
    }
  };

  auto supervisor =
      test::start_pipeline("synth", dataset, dir.path(), "tf", domain, {"loop_closer=heslam-loop-closer-proximity"});
  const auto run_deadline = std::chrono::steady_clock::now() + test::kPipelineTimeout;
  std::optional<int> code;
  while (!(code = supervisor->wait(milliseconds(100))) && std::chrono::steady_clock::now() < run_deadline) drain();
  if (!code) code = test::finish(*supervisor, seconds(0));
  ASSERT_EQ(code.value_or(-1), 0) << supervisor->out() << supervisor->err();
  // The bridge's last samples: every frame's odometry and, for each tracked one, its TF (bounded against
  // a hang; a run short of them fails below).
  const auto all_in = [&] {
    if (odometry_by_stamp.size() < static_cast<std::size_t>(kCorridorFrames)) return false;
    for (const auto& [stamp, odometry] : odometry_by_stamp) {
      if (odometry.state != heslam_msg_TRACKING_OK) continue;
      const auto found = tf_by_stamp.find(stamp);
      if (found == tf_by_stamp.end() || !found->second.T_map_odom || !found->second.T_odom_base) return false;
    }
    return true;
  };
  const auto samples_deadline = std::chrono::steady_clock::now() + seconds(30);
  drain();
  while (!all_in() && std::chrono::steady_clock::now() < samples_deadline) {
    std::this_thread::sleep_for(milliseconds(50));
    drain();
  }
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait(seconds(20)).value_or(-1), 0) << bridge.err();
  const std::string output = supervisor->out() + supervisor->err();

  ASSERT_TRUE(T_base_camera && T_map_world) << "no base_link -> heslam_camera / map -> heslam_world on rt/tf_static";
  // Both static transforms are T_B_rect (tf_tree.hpp).
  EXPECT_LT(max_abs_difference(*T_base_camera, *T_map_world), 1e-12);

  // Every tracked frame has its TF, composing to the pose the frontend published.
  std::size_t tracked = 0;
  double worst_compose = 0.0;
  for (const auto& [stamp, odometry] : odometry_by_stamp) {
    if (odometry.state != heslam_msg_TRACKING_OK) continue;
    ++tracked;
    const auto found = tf_by_stamp.find(stamp);
    ASSERT_TRUE(found != tf_by_stamp.end() && found->second.T_map_odom && found->second.T_odom_base)
        << "no map -> odom -> base_link at stamp " << stamp;
    const Pose3 T_map_camera = *found->second.T_map_odom * *found->second.T_odom_base * *T_base_camera;
    const Pose3 expected = *T_map_world * messages::to_pose(odometry.T_wc);
    worst_compose = std::max(worst_compose, max_abs_difference(T_map_camera, expected));
  }
  EXPECT_EQ(tracked, static_cast<std::size_t>(kCorridorFrames)) << output;
  EXPECT_LT(worst_compose, kComposeTolerance);

  // Across the loop correction: each step of the camera in odom is as long as the true step (within the
  // tracking error), while map -> odom jumps by the correction.
  const eval::Trajectory truth = test::camera_ground_truth(dataset);
  ASSERT_EQ(truth.size(), static_cast<std::size_t>(kCorridorFrames));
  std::vector<Pose3> odom_camera;
  std::vector<Pose3> map_odom;
  std::vector<Pose3> map_camera;
  for (const auto& [stamp, frame] : tf_by_stamp) {
    if (!frame.T_map_odom || !frame.T_odom_base) continue;
    odom_camera.push_back(*frame.T_odom_base * *T_base_camera);
    map_odom.push_back(*frame.T_map_odom);
    map_camera.push_back(*frame.T_map_odom * *frame.T_odom_base * *T_base_camera);
  }
  ASSERT_EQ(odom_camera.size(), truth.size());
  double largest_true_step = 0.0, worst_odom_step_error = 0.0, worst_map_step_error = 0.0, largest_correction = 0.0;
  for (std::size_t k = 1; k < truth.size(); ++k) {
    const double true_step = (truth.poses_wc[k].translation() - truth.poses_wc[k - 1].translation()).norm();
    const double odom_step = (odom_camera[k].translation() - odom_camera[k - 1].translation()).norm();
    const double map_step = (map_camera[k].translation() - map_camera[k - 1].translation()).norm();
    largest_true_step = std::max(largest_true_step, true_step);
    worst_odom_step_error = std::max(worst_odom_step_error, std::abs(odom_step - true_step));
    worst_map_step_error = std::max(worst_map_step_error, std::abs(map_step - true_step));
    largest_correction =
        std::max(largest_correction, (map_odom[k].translation() - map_odom[k - 1].translation()).norm());
  }
  std::printf(
      "[ figures  ] corridor_loop TF: largest true step %.1f mm; odom -> base_link step error at most %.2f mm, "
      "map -> base_link %.2f mm; largest map -> odom change %.1f mm\n",
      largest_true_step * 1e3, worst_odom_step_error * 1e3, worst_map_step_error * 1e3, largest_correction * 1e3);
  // A correction landed (else this test shows nothing) and it is not in odom.
  EXPECT_GT(largest_correction, 4.0 * worst_odom_step_error) << output;
  EXPECT_LT(worst_odom_step_error, largest_true_step);
  EXPECT_LT(worst_odom_step_error, worst_map_step_error);

  // The proximity loop closer closes the loop (was CorridorLoop.ProximityLoopCloserClosesTheSameLoop, a
  // second run of this pipeline with the same arguments): the recorder's trajectory against the truth.
  const double path_m = truth.path_length_m();
  const double ate_m = test::ate_rmse_m(dataset, dir.path() / "tf.txt");
  std::printf(
      "[ figures  ] corridor_loop: with heslam-loop-closer-proximity ATE rmse %.1f mm (%.3f %% of %.1f m), "
      "%d loop(s) accepted\n",
      ate_m * 1e3, 100.0 * ate_m / path_m, path_m, loops_accepted(output));
  EXPECT_EQ(eval::read_trajectory(dir.path() / "tf.txt").size(), truth.size());
  EXPECT_GE(loops_accepted(output), 1) << output;
  EXPECT_LT(ate_m, kMaxAteOfPath * path_m);
}

}  // namespace
}  // namespace heslam::ros2
