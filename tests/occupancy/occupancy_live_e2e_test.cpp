// heslam-occupancy's live outputs in a real run: the full synthetic system (lockstep) on the room with
// heslam-occupancy and heslam-ros2-bridge beside it, and two readers that know only the wire types:
// heslam's map/occupancy_grid and ROS 2's /map (nav_msgs/OccupancyGrid, transient local). The last grid
// of each equals the map the process saved (STEM.pgm + STEM.yaml) cell by cell, with its size,
// resolution and origin. And its bad input: a process fed malformed samples counts and skips each
// with one line, and still writes its map.
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/pose.hpp"
#include "components/occupancy/occupancy_messages.hpp"
#include "pipeline_runs.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/dataset/stereo_images.hpp"
#include "tools/replay/replay_messages.hpp"
#include "tools/ros2_bridge/ros2_messages.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr int kRoomFrames = 150;
// Bounds of a hung process or a sample that never comes, not performance assertions.
constexpr seconds kMatchTimeout{30};
constexpr seconds kSampleTimeout{60};
// OccupancyLoopCorrection: the least the corrected grid's IoU must exceed the drifted one's by: half of
// the +0.0207 measured (0.1937 -> 0.2144; docs/occupancy.md "A loop correction"). Deterministic, so the
// half is for changes of the matcher or the fusion, not for load.
constexpr double kLoopCorrectionMargin = 0.010;

struct Pgm {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;
};

Pgm read_pgm(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string magic, comment;
  Pgm pgm;
  int max_value = 0;
  in >> magic;
  in.get();
  if (in.peek() == '#') std::getline(in, comment);
  in >> pgm.width >> pgm.height >> max_value;
  in.get();
  pgm.pixels.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return pgm;
}

// origin: [x, y, 0.0] and resolution of a map_server YAML.
struct MapYaml {
  double resolution = 0.0;
  double origin_x = 0.0, origin_y = 0.0;
};
MapYaml read_map_yaml(const fs::path& file) {
  std::ifstream in(file);
  MapYaml yaml;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("resolution:", 0) == 0) yaml.resolution = std::stod(line.substr(11));
    if (line.rfind("origin:", 0) == 0) {
      std::string values = line.substr(line.find('[') + 1);
      std::replace(values.begin(), values.end(), ',', ' ');
      std::istringstream(values) >> yaml.origin_x >> yaml.origin_y;
    }
  }
  return yaml;
}

// A transient-local (latched) reader of one ROS 2 type that keeps a copy of the newest sample's fields.
class LatchedRos2Reader {
 public:
  LatchedRos2Reader(const runtime::Participant& participant, const dds_topic_descriptor_t* descriptor,
                    const std::string& topic)
      : descriptor_(descriptor) {
    topic_ = runtime::Entity(dds_create_topic(participant.handle(), descriptor, topic.c_str(), nullptr, nullptr));
    runtime::Qos qos = runtime::Qos(runtime::QosRole::kCalibration).keep_last(1).transient_local(1);
    reader_ = runtime::Entity(dds_create_reader(participant.handle(), topic_.get(), qos.get(), nullptr));
  }
  template <typename T, typename Use>
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

 private:
  const dds_topic_descriptor_t* descriptor_;
  runtime::Entity topic_;
  runtime::Entity reader_;
};

struct RosGrid {
  std::string frame_id;
  float resolution = 0.f;
  std::uint32_t width = 0, height = 0;
  Pose3 origin = Pose3::Identity();
  std::vector<std::int8_t> data;
};

Pose3 to_pose3(const ros2::Pose& p) {
  Pose3 T = Pose3::Identity();
  T.linear() =
      Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}

Pose3 to_pose3(const ros2::Transform& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::Quaterniond(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z).toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return T;
}

// The wire value of a PGM pixel (map_server trinary: 0 occupied, 254 free, 205 unknown) as nav_msgs has it.
int ros_value_of_pixel(std::uint8_t pixel) { return pixel == 0 ? 100 : pixel == 254 ? 0 : -1; }

TEST(OccupancyLiveEndToEnd, RoomGridOnDdsAndOnRos2MapEqualsTheSavedMap) {
  fs::path dataset;
  const std::string render_error = test::cached_synth("room", kRoomFrames, dataset);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("occupancy_live_room");
  const int domain = test::exclusive_domain_id();
  runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  const runtime::Topics topics;
  runtime::Reader<msg::OccupancyGrid2D> grid_reader(participant, topics.occupancy_grid());
  runtime::Reader<msg::DenseCloud> cloud_reader(participant, topics.dense_cloud());
  LatchedRos2Reader map_reader(participant, &nav_msgs_msg_dds__OccupancyGrid__desc, "rt/map");
  LatchedRos2Reader tf_static_reader(participant, &tf2_msgs_msg_dds__TFMessage__desc, "rt/tf_static");
  LatchedRos2Reader dense_reader(participant, &sensor_msgs_msg_dds__PointCloud2__desc, "rt/heslam/dense_cloud");

  test::ChildProcess bridge(test::bin_dir() / "heslam-ros2-bridge", {"--domain", std::to_string(domain)}, dir.path(),
                            "bridge");
  std::optional<occupancy::ReceivedGrid> last_grid;
  std::uint64_t grids = 0, last_revision = 0, clouds = 0, dense_points = 0;
  std::uint32_t cloud_points = 0, cloud_total = 0;
  std::optional<RosGrid> last_map;
  std::optional<Pose3> T_map_world;
  const auto drain = [&] {
    for (auto& received : grid_reader.take()) {
      if (!received.info.valid_data) continue;
      EXPECT_GT(received.sample->revision, last_revision);  // revisions only grow
      last_revision = received.sample->revision;
      last_grid = occupancy::from_message(*received.sample);
      ++grids;
    }
    for (auto& received : cloud_reader.take()) {
      if (!received.info.valid_data) continue;
      ++clouds;
      cloud_points = received.sample->xyz_w_m._length / 3;
      cloud_total = received.sample->total_points;
    }
    map_reader.take_all<ros2::OccupancyGrid>([&](const ros2::OccupancyGrid& m) {
      RosGrid grid{m.header.frame_id == nullptr ? "" : m.header.frame_id,
                   m.info.resolution,
                   m.info.width,
                   m.info.height,
                   to_pose3(m.info.origin),
                   {}};
      grid.data.assign(m.data._buffer, m.data._buffer + m.data._length);
      last_map = std::move(grid);
    });
    dense_reader.take_all<ros2::PointCloud2>([&](const ros2::PointCloud2& m) { dense_points = m.width; });
    tf_static_reader.take_all<ros2::TFMessage>([&](const ros2::TFMessage& message) {
      for (std::uint32_t i = 0; i < message.transforms._length; ++i) {
        const ros2::TransformStamped& t = message.transforms._buffer[i];
        if (std::string(t.header.frame_id) == "map" && std::string(t.child_frame_id) == "heslam_world") {
          T_map_world = to_pose3(t.transform);
        }
      }
    });
  };

  auto supervisor = test::start_pipeline("synth", dataset, dir.path(), "room", domain,
                                         {"occupancy=heslam-occupancy", "loop_closer=none"});
  const auto run_deadline = std::chrono::steady_clock::now() + test::kPipelineTimeout;
  std::optional<int> code;
  while (!(code = supervisor->wait(milliseconds(100))) && std::chrono::steady_clock::now() < run_deadline) drain();
  if (!code) code = test::finish(*supervisor, seconds(0));
  ASSERT_EQ(code.value_or(-1), 0) << supervisor->out() << supervisor->err();

  // The saved map, and the grid the readers must end on.
  const fs::path stem = dir.path() / "room";
  ASSERT_TRUE(fs::exists(stem.string() + ".pgm")) << supervisor->err();
  const OccupancyGrid saved = OccupancyGrid::read_map_server(stem.string() + ".yaml");
  const Pgm pgm = read_pgm(stem.string() + ".pgm");
  const MapYaml yaml = read_map_yaml(stem.string() + ".yaml");
  ASSERT_GT(saved.count(CellState::kOccupied), 0u);
  // The final grid was written before the process exited (it waits for the readers' acknowledgement);
  // the bridge republishes what it receives. Wait (bounded) for both to show it.
  const auto sample_deadline = std::chrono::steady_clock::now() + kSampleTimeout;
  std::vector<std::int8_t> expected_data(pgm.pixels.size());
  for (int row = 0; row < pgm.height; ++row) {
    for (int col = 0; col < pgm.width; ++col) {
      const std::uint8_t pixel = pgm.pixels[static_cast<std::size_t>((pgm.height - 1 - row) * pgm.width + col)];
      expected_data[static_cast<std::size_t>(row * pgm.width + col)] =
          static_cast<std::int8_t>(ros_value_of_pixel(pixel));
    }
  }
  const auto ros_matches = [&] { return last_map && last_map->data == expected_data; };
  while (!(last_grid && last_grid->grid.cells() == saved.cells() && ros_matches() && T_map_world && cloud_points > 0 &&
           dense_points == cloud_points) &&
         std::chrono::steady_clock::now() < sample_deadline) {
    std::this_thread::sleep_for(milliseconds(100));
    drain();
  }
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait(seconds(20)).value_or(-1), 0) << bridge.err();

  // heslam's topic: the last grid is the saved one, cell by cell; the grid frame of a -y-up map.
  ASSERT_TRUE(last_grid) << "no sample on " << topics.occupancy_grid().name << "\n" << supervisor->err();
  EXPECT_EQ(last_grid->grid.cells(), saved.cells());
  EXPECT_DOUBLE_EQ(last_grid->grid.resolution_m(), yaml.resolution);
  Eigen::Matrix3d R_wg;
  R_wg << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  EXPECT_LT((last_grid->T_wg.linear() - R_wg).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GE(grids, 1u);
  // The cloud: bounded by live.cloud_max_points (200000 by default), total as many as the PLY has.
  EXPECT_GE(clouds, 1u);
  EXPECT_LE(cloud_points, 200000u);
  EXPECT_GT(cloud_points, 0u);
  EXPECT_GE(cloud_total, cloud_points);
  EXPECT_EQ(dense_points, cloud_points) << "rt/heslam/dense_cloud: the bridge's copy of the newest cloud";

  // ROS 2's /map: the saved PGM's size, resolution, cells (rows from the bottom) and origin in map.
  ASSERT_TRUE(last_map) << "no nav_msgs/OccupancyGrid on rt/map\n" << bridge.err();
  ASSERT_TRUE(T_map_world) << "no map -> heslam_world on rt/tf_static";
  EXPECT_EQ(last_map->frame_id, "map");
  EXPECT_FLOAT_EQ(last_map->resolution, static_cast<float>(yaml.resolution));
  ASSERT_EQ(static_cast<int>(last_map->width), pgm.width);
  ASSERT_EQ(static_cast<int>(last_map->height), pgm.height);
  ASSERT_EQ(last_map->data.size(), pgm.pixels.size());
  std::size_t differing = 0;
  for (std::size_t k = 0; k < expected_data.size(); ++k) differing += last_map->data[k] != expected_data[k];
  EXPECT_EQ(differing, 0u) << "cells of /map that differ from the saved PGM";
  Pose3 T_wg = Pose3::Identity();
  T_wg.linear() = R_wg;
  const Pose3 expected_origin = *T_map_world * T_wg * Eigen::Translation3d(yaml.origin_x, yaml.origin_y, 0.0);
  EXPECT_LT((last_map->origin.matrix() - expected_origin.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  std::printf(
      "[ figures  ] room %d frames: %llu grid samples (last revision %llu), %llu clouds (%u of %u points); "
      "/map %ux%u cells at %.3f m\n",
      kRoomFrames, static_cast<unsigned long long>(grids), static_cast<unsigned long long>(last_revision),
      static_cast<unsigned long long>(clouds), cloud_points, cloud_total, last_map->width, last_map->height,
      last_map->resolution);
}

// --- Bad input -------------------------------------------------------------------------------------

msg::Keyframe minimal_keyframe(std::uint64_t id, std::int64_t stamp_ns, const PinholeStereo& camera) {
  msg::Keyframe keyframe{};
  keyframe.id = id;
  keyframe.stamp_ns = stamp_ns;
  keyframe.T_wc = messages::to_message(Pose3::Identity());
  keyframe.camera = messages::to_message(camera);
  keyframe.pyramid_levels = 1;
  keyframe.scale_factor = 1.2f;
  return keyframe;
}

bool err_contains_within(const test::ChildProcess& process, const std::string& text, seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (process.err().find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(milliseconds(50));
  }
  return false;
}

// A heslam-occupancy process on its own domain fed by the test in place of the replay, the frontend and
// the mapper: writers of their topics, a reader of its status, the process (the synth layers, then
// `extra_configs`, output STEM).
struct FedOccupancy {
  FedOccupancy(int domain, const fs::path& dir, const fs::path& stem, const std::vector<fs::path>& extra_configs = {})
      : participant({.domain_id = domain, .dds_config = ""}),
        calibration_writer(participant, topics.calibration()),
        frame_writer(participant, topics.stereo()),
        keyframe_writer(participant, topics.keyframes()),
        state_writer(participant, topics.keyframe_states()),
        status_reader(participant, topics.status()),
        process(test::bin_dir() / "heslam-occupancy", arguments(domain, stem, extra_configs), dir, "occupancy") {}

  static std::vector<std::string> arguments(int domain, const fs::path& stem, const std::vector<fs::path>& extra) {
    std::vector<std::string> args{"--domain", std::to_string(domain)};
    for (const char* layer : {"default.yaml", "synth.yaml"}) {
      args.insert(args.end(), {"--config", (test::source_dir() / "config/occupancy" / layer).string()});
    }
    for (const fs::path& config : extra) args.insert(args.end(), {"--config", config.string()});
    args.insert(args.end(), {"--output-stem", stem.string()});
    return args;
  }
  // Every writer matched by the process (each within kMatchTimeout).
  bool matched() const {
    return frame_writer.wait_for_readers(1, kMatchTimeout) && keyframe_writer.wait_for_readers(1, kMatchTimeout) &&
           state_writer.wait_for_readers(1, kMatchTimeout) && calibration_writer.wait_for_readers(1, kMatchTimeout);
  }

  runtime::Topics topics;
  runtime::Participant participant;
  runtime::Writer<msg::StereoCalibration> calibration_writer;
  runtime::Writer<msg::StereoFrame> frame_writer;
  runtime::Writer<msg::Keyframe> keyframe_writer;
  runtime::Writer<msg::KeyframeState> state_writer;
  runtime::Reader<msg::ComponentStatus> status_reader;
  test::ChildProcess process;
};

// Keyframes without their frame, frames of the wrong size, NaN poses (keyframe and state), states of
// keyframes never sent: each counted (its status' counters) and skipped with one line naming the
// topic; one good keyframe still makes the map, and the process exits 0.
TEST(OccupancyBadInput, EachBadSampleIsCountedAndSkippedAndTheMapIsStillWritten) {
  fs::path dataset_path;
  const std::string render_error = test::cached_synth("room", 20, dataset_path);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("occupancy_bad_input");
  const int domain = test::exclusive_domain_id();
  const StereoDataset dataset = open_dataset(dataset_path);
  const StereoRectifier rectifier(dataset.calibration);
  const CalibrationMessage calibration(dataset.calibration, rectifier.camera());
  const fs::path stem = dir.path() / "bad";
  FedOccupancy fed(domain, dir.path(), stem);
  test::ChildProcess& occupancy = fed.process;
  ASSERT_TRUE(fed.matched()) << occupancy.err();
  fed.calibration_writer.write(calibration.get());

  const StereoImages first = load_stereo_images(dataset.frames[0]);
  const std::int64_t stamp0 = dataset.frames[0].stamp_ns;
  const std::int64_t stamp1 = dataset.frames[1].stamp_ns;
  // 1. A frame of the wrong size (half the calibration's): bad_frames.
  cv::Mat small_left, small_right;
  cv::resize(first.left, small_left, first.left.size() / 2);
  cv::resize(first.right, small_right, first.right.size() / 2);
  const StereoImages small{small_left, small_right, first.encoding};
  // The frame check needs the calibration: sent first, taken when the process says so.
  ASSERT_TRUE(err_contains_within(occupancy, "calibration: raw", kSampleTimeout)) << occupancy.err();
  fed.frame_writer.write(make_frame_message(small, stamp0 - 1000, stamp0 - 1000, 0));
  ASSERT_TRUE(err_contains_within(occupancy, "the calibration says", kSampleTimeout)) << occupancy.err();
  // 2. A keyframe with a NaN pose: bad_keyframes (the shared message check).
  msg::Keyframe nan_keyframe = minimal_keyframe(1001, stamp0, rectifier.camera());
  nan_keyframe.T_wc.position_m[0] = std::nan("");
  fed.keyframe_writer.write(nan_keyframe);
  // 3. A state with a NaN pose: bad_keyframe_states; a state of a keyframe never sent: counted at the end.
  msg::KeyframeState nan_state{};
  nan_state.id = 1002;
  nan_state.T_wc = messages::to_message(Pose3::Identity());
  nan_state.T_wc.orientation_xyzw[3] = std::nan("");
  fed.state_writer.write(nan_state);
  msg::KeyframeState unknown_state{};
  unknown_state.id = 4242;
  unknown_state.T_wc = messages::to_message(Pose3::Identity());
  fed.state_writer.write(unknown_state);
  // 4. A keyframe whose frame never comes (stamp before the frames sent next): keyframes_without_frame.
  fed.keyframe_writer.write(minimal_keyframe(1003, stamp0 - 500, rectifier.camera()));
  // 5. A good keyframe with its frame: the map.
  fed.frame_writer.write(make_frame_message(first, stamp0, stamp0, 1));
  fed.keyframe_writer.write(minimal_keyframe(1004, stamp0, rectifier.camera()));
  const StereoImages second = load_stereo_images(dataset.frames[1]);
  fed.frame_writer.write(make_frame_message(second, stamp1, stamp1, 2));
  // The counters, as its status publishes them (once a second), until each bad sample is counted.
  std::map<std::string, std::uint64_t> counters;
  const std::map<std::string, std::uint64_t> expected{{"bad_frames", 1},
                                                      {"bad_keyframes", 1},
                                                      {"bad_keyframe_states", 1},
                                                      {"keyframes_without_frame", 1},
                                                      {"clouds", 1}};
  const auto all_counted = [&] {
    for (const auto& [name, value] : expected) {
      if (counters[name] < value) return false;
    }
    return true;
  };
  const auto deadline = std::chrono::steady_clock::now() + kSampleTimeout;
  while (!all_counted() && std::chrono::steady_clock::now() < deadline) {
    for (auto& received : fed.status_reader.take()) {
      if (!received.info.valid_data || runtime::to_string(received.sample->name) != "occupancy") continue;
      for (const msg::Counter& c : runtime::view(received.sample->counters)) {
        counters[runtime::to_string(c.name)] = c.value;
      }
    }
    std::this_thread::sleep_for(milliseconds(100));
  }
  for (const auto& [name, value] : expected) EXPECT_EQ(counters[name], value) << name << "\n" << occupancy.err();

  occupancy.signal(SIGTERM);
  EXPECT_EQ(occupancy.wait(seconds(60)).value_or(-1), 0) << occupancy.err();
  const std::string err = occupancy.err();
  // One line each, naming the topic; the state of a keyframe never sent is told at the end.
  EXPECT_NE(err.find("topic 'heslam/camera/stereo': frame seq 0: "), std::string::npos) << err;
  EXPECT_NE(err.find("topic 'heslam/map/keyframes': "), std::string::npos) << err;
  EXPECT_NE(err.find("topic 'heslam/map/keyframe_states': "), std::string::npos) << err;
  EXPECT_NE(err.find("(counted as keyframes_without_frame)"), std::string::npos) << err;
  EXPECT_NE(err.find("1 keyframe state(s) (pose, correction or cull) of keyframes never received"), std::string::npos)
      << err;
  EXPECT_TRUE(fs::exists(stem.string() + ".pgm")) << err;
  EXPECT_TRUE(fs::exists(stem.string() + ".ply")) << err;
}

// A loop correction in the process, the known answer without a SLAM run: six frames of the synthetic
// room sent as keyframes 1-6 at their true poses, then the same frames again (new stamps) as keyframes
// 11-16 whose first poses drifted 0.35 m (7 cells along both grid axes), as an uncorrected loop would
// place them; then the mapper's states for 11-16 at the true poses, as a correction. STEM.first_poses
// (first_poses_grid: every cloud at its first pose) has the room's walls twice; STEM.pgm, fused again at
// the corrected poses, has them once: its IoU against the room's truth is higher by a margin and it has a
// third fewer occupied cells. (Its truth cells called free are more, 110 -> 315: the copy's hits had
// covered some of the cells the true views carve.) Deterministic: the final map is fused in keyframe id
// order from clouds of fixed frames, whatever the load.
TEST(OccupancyLoopCorrection, CorrectedPosesRemoveTheDoubledWallsOfTheDriftedKeyframes) {
  fs::path dataset_path;
  const std::string render_error = test::cached_synth("room", kRoomFrames, dataset_path);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("occupancy_loop_correction");
  const int domain = test::exclusive_domain_id();
  const StereoDataset dataset = open_dataset(dataset_path);
  const StereoRectifier rectifier(dataset.calibration);
  const CalibrationMessage calibration(dataset.calibration, rectifier.camera());
  // True left-camera poses in the first left camera's frame (the SLAM world and the truth's grid frame).
  const eval::Trajectory truth = test::camera_ground_truth(dataset_path);
  ASSERT_FALSE(truth.empty());
  const auto true_pose = [&](std::int64_t stamp_ns) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < truth.size(); ++i) {
      if (std::abs(truth.stamps_s[i] - stamp_ns * 1e-9) < std::abs(truth.stamps_s[best] - stamp_ns * 1e-9)) best = i;
    }
    return Pose3(truth.poses_wc.front().inverse() * truth.poses_wc[best]);
  };
  const fs::path overlay = dir.path() / "first_poses.yaml";
  std::ofstream(overlay) << "%YAML:1.0\n---\nfirst_poses_grid: true\n";
  const fs::path stem = dir.path() / "loop";
  FedOccupancy fed(domain, dir.path(), stem, {overlay});
  test::ChildProcess& occupancy = fed.process;
  ASSERT_TRUE(fed.matched()) << occupancy.err();
  fed.calibration_writer.write(calibration.get());
  ASSERT_TRUE(err_contains_within(occupancy, "calibration: raw", kSampleTimeout)) << occupancy.err();

  const std::vector<std::size_t> frames{0, 20, 40, 60, 80, 100};
  const Eigen::Vector3d drift(0.35, 0.0, 0.35);            // world x and z: both axes of the -y-up grid
  constexpr std::int64_t kSecondPassNs = 100'000'000'000;  // the frames again, 100 s later
  auto counters = [&] {
    std::map<std::string, std::uint64_t> latest;
    for (auto& received : fed.status_reader.take()) {
      if (!received.info.valid_data || runtime::to_string(received.sample->name) != "occupancy") continue;
      latest.clear();
      for (const msg::Counter& c : runtime::view(received.sample->counters))
        latest[runtime::to_string(c.name)] = c.value;
    }
    return latest;
  };
  auto wait_for = [&](const std::string& counter, std::uint64_t value) {
    const auto deadline = std::chrono::steady_clock::now() + kSampleTimeout * 3;
    std::uint64_t seen = 0;
    while (seen < value && std::chrono::steady_clock::now() < deadline) {
      const auto latest = counters();
      if (const auto found = latest.find(counter); found != latest.end()) seen = found->second;
      std::this_thread::sleep_for(milliseconds(100));
    }
    return seen >= value;
  };
  std::uint32_t seq = 0;
  for (const bool second : {false, true}) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const StereoFrameFiles& files = dataset.frames[frames[k]];
      const std::int64_t stamp = files.stamp_ns + (second ? kSecondPassNs : 0);
      fed.frame_writer.write(make_frame_message(load_stereo_images(files), stamp, stamp, seq++));
      msg::Keyframe keyframe = minimal_keyframe((second ? 11 : 1) + k, stamp, rectifier.camera());
      Pose3 first = true_pose(files.stamp_ns);
      if (second) first.translation() += drift;
      keyframe.T_wc = messages::to_message(first);
      fed.keyframe_writer.write(keyframe);
      // One keyframe at a time: its frame is in the ring when it comes.
      ASSERT_TRUE(wait_for("clouds", (second ? frames.size() : 0) + k + 1)) << occupancy.err();
    }
  }
  // The correction, as the mapper publishes it: 11-16 at their true poses.
  for (std::size_t k = 0; k < frames.size(); ++k) {
    msg::KeyframeState state{};
    state.id = 11 + k;
    state.T_wc = messages::to_message(true_pose(dataset.frames[frames[k]].stamp_ns));
    fed.state_writer.write(state);
  }
  ASSERT_TRUE(wait_for("keyframe_states", frames.size())) << occupancy.err();
  occupancy.signal(SIGTERM);
  ASSERT_EQ(occupancy.wait(seconds(300)).value_or(-1), 0) << occupancy.err();

  test::ChildProcess synth(test::bin_dir() / "heslam-synth",
                           {"--preset", "room", "--occupancy-gt", (dir.path() / "gt").string()}, dir.path(),
                           "synth_gt");
  ASSERT_EQ(synth.wait(seconds(120)).value_or(-1), 0) << synth.err();
  const OccupancyGrid room = OccupancyGrid::read_map_server(dir.path() / "gt.yaml");
  const GridAgreement before = compare(OccupancyGrid::read_map_server(stem.string() + ".first_poses.yaml"), room);
  const GridAgreement after = compare(OccupancyGrid::read_map_server(stem.string() + ".yaml"), room);
  std::printf(
      "[ figures  ] 6 room frames twice, the second time 0.35 m off (x and z), then corrected: occupied IoU %.4f at "
      "the first poses (%zu grid cells, %zu truth cells free) -> %.4f corrected (%zu grid cells, %zu free)\n",
      before.occupied_iou, before.grid_occupied, before.free_in_truth_occupied, after.occupied_iou, after.grid_occupied,
      after.free_in_truth_occupied);
  EXPECT_GT(after.occupied_iou, before.occupied_iou + kLoopCorrectionMargin);
  // The copy of the walls gone: a third fewer occupied cells (6858 -> 4681 measured).
  EXPECT_LT(after.grid_occupied * 4, before.grid_occupied * 3);
  EXPECT_NE(occupancy.err().find("the farthest moved 0.49"), std::string::npos) << occupancy.err();
}

}  // namespace
}  // namespace heslam
