// heslam-viewer as a real process beside a lockstep MH01 run (euroc pipeline, the full system): started by hand
// while the run goes (it gets the map from the transient-local topics), on an Xvfb display when Xvfb
// is installed (viz 3D window + highgui), else headless, plus a second headless viewer with the
// ground truth that is up before the run starts (so it sees the frames whatever the machine's load).
// Asserts on the pictures and counts, and that the pipeline's output is bit-identical with and without
// viewers.
#include <gtest/gtest.h>

#include <signal.h>
#include <stdlib.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pipeline_runs.hpp"
#include "test_support.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/viewer/colours.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using test::ChildProcess;

// The viewer is started this long after the pipeline: usually mid-run (a late joiner), but the
// assertions hold whenever it joins.
constexpr std::chrono::milliseconds kViewerStartDelay{3000};
constexpr std::chrono::seconds kViewerStop{30};
constexpr std::chrono::seconds kXvfbStart{5};
constexpr std::chrono::seconds kViewerReady{20};

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::map<std::string, std::string> read_stats(const fs::path& path) {
  std::map<std::string, std::string> stats;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    const auto eq = line.find('=');
    if (eq != std::string::npos) stats[line.substr(0, eq)] = line.substr(eq + 1);
  }
  return stats;
}

int data_rows(const fs::path& file) {
  std::ifstream in(file);
  int rows = 0;
  for (std::string line; std::getline(in, line);) rows += (!line.empty() && line[0] != '#') ? 1 : 0;
  return rows;
}

// The dataset's left image of frame `seq` (the replay publishes the frames in this order).
cv::Mat dataset_left(const fs::path& dataset, int seq) {
  DatasetOptions options;
  options.load_calibration = false;
  const StereoDataset frames = open_dataset(dataset, options);
  if (seq < 0 || static_cast<std::size_t>(seq) >= frames.frames.size()) return {};
  return cv::imread(frames.frames[static_cast<std::size_t>(seq)].left.string(), cv::IMREAD_GRAYSCALE);
}

int pixels_of(const cv::Mat& image, const cv::Scalar& bgr) {
  cv::Mat mask;
  cv::inRange(image, bgr, bgr, mask);
  return cv::countNonZero(mask);
}

// The raw half of a viewer's frame picture is the dataset's left image of the frame it names, pixel for pixel.
void expect_frame_view_shows_its_frame(const fs::path& picture, const fs::path& dataset, const std::string& frame_seq) {
  const cv::Mat frame = cv::imread(picture.string());
  ASSERT_FALSE(frame.empty()) << picture;
  const int seq = std::stoi(frame_seq);
  const cv::Mat expected = dataset_left(dataset, seq);
  ASSERT_FALSE(expected.empty()) << "frame " << seq;
  cv::Mat expected_bgr;
  cv::cvtColor(expected, expected_bgr, cv::COLOR_GRAY2BGR);
  EXPECT_EQ(cv::norm(frame(cv::Rect(0, 0, expected.cols, expected.rows)), expected_bgr, cv::NORM_INF), 0.0) << picture;
}

// An Xvfb server on a display number derived from the test's exclusive DDS domain, or nothing when
// Xvfb is not installed or does not come up. The number is ours alone (the domain lock), so a socket
// or lock file left by a killed earlier server is stale: removed first, or the socket would look ready.
std::unique_ptr<ChildProcess> start_xvfb(const fs::path& dir, std::string& display) {
  const fs::path xvfb = "/usr/bin/Xvfb";
  if (!fs::exists(xvfb)) return nullptr;
  const int number = 300 + test::exclusive_domain_id();
  display = std::string(1, ':').append(std::to_string(number));  // (not ":" + ...: GCC 12 -Wrestrict false positive)
  std::error_code ignored;
  fs::remove(fs::path("/tmp/.X11-unix") / std::string(1, 'X').append(std::to_string(number)), ignored);
  fs::remove(fs::path("/tmp") / std::string(".X").append(std::to_string(number)).append("-lock"), ignored);
  auto server = std::make_unique<ChildProcess>(
      xvfb, std::vector<std::string>{display, "-screen", "0", "1920x1200x24", "-nolisten", "tcp"}, dir, "xvfb");
  const auto deadline = std::chrono::steady_clock::now() + kXvfbStart;
  const fs::path socket = fs::path("/tmp/.X11-unix") / std::string(1, 'X').append(std::to_string(number));
  while (!fs::exists(socket) && std::chrono::steady_clock::now() < deadline &&
         !server->wait(std::chrono::milliseconds(0))) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (!fs::exists(socket)) return nullptr;
  return server;
}

TEST(ViewerEndToEnd, JoinsAMh01RunDrawsEveryKeyframeAndLeavesTheOutputBitIdentical) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("viewer");
  const int domain = test::exclusive_domain_id();

  // Without the viewer.
  auto plain = test::start_pipeline("euroc", dataset, dir.path(), "plain", domain);
  ASSERT_EQ(test::finish(*plain), 0) << plain->out() << plain->err();

  // With the viewer, started by hand while the run goes; on Xvfb when there is one.
  std::string display;
  std::unique_ptr<ChildProcess> xvfb = start_xvfb(dir.path(), display);
  if (xvfb) {
    setenv("DISPLAY", display.c_str(), 1);
  } else {
    unsetenv("DISPLAY");
  }
  // A headless viewer with the ground truth overlaid, up before the run: a viewer that joins mid-run
  // may, on a loaded machine, join after the last frame (CI saw 1 of 160), so the frame and trajectory
  // checks are made on this one.
  const std::vector<std::string> headless_args{"--domain",
                                               std::to_string(domain),
                                               "--headless",
                                               "--out",
                                               (dir.path() / "headless").string(),
                                               "--gt",
                                               (dataset / "mav0/state_groundtruth_estimate0/data.csv").string(),
                                               "--gt-extrinsic",
                                               (dataset / "mav0/cam0/sensor.yaml").string()};
  ChildProcess headless(test::bin_dir() / "heslam-viewer", headless_args, dir.path(), "headless_viewer");
  const auto ready_deadline = std::chrono::steady_clock::now() + kViewerReady;
  while (headless.err().find("info: headless") == std::string::npos &&
         std::chrono::steady_clock::now() < ready_deadline && !headless.wait(std::chrono::milliseconds(0))) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_NE(headless.err().find("info: headless"), std::string::npos) << headless.out() << headless.err();

  auto viewed = test::start_pipeline("euroc", dataset, dir.path(), "viewed", domain);
  std::this_thread::sleep_for(kViewerStartDelay);
  std::vector<std::string> viewer_args{"--domain",
                                       std::to_string(domain),
                                       "--out",
                                       (dir.path() / "pictures").string(),
                                       "--snapshot-every",
                                       "2",
                                       "--fit",
                                       "map",
                                       "--record",
                                       (dir.path() / "frames.mp4").string()};
  if (!xvfb) viewer_args.push_back("--headless");
  ChildProcess viewer(test::bin_dir() / "heslam-viewer", viewer_args, dir.path(), "viewer");
  const int pipeline_code = test::finish(*viewed);
  // Both viewers end with the run they watch (the supervisor's status says it is ending the run).
  const std::optional<int> viewer_code = viewer.wait(kViewerStop);
  const std::optional<int> headless_code = headless.wait(kViewerStop);
  if (!viewer_code) viewer.signal(SIGTERM);
  if (!headless_code) headless.signal(SIGTERM);
  if (!viewer_code || !headless_code) {
    viewer.wait(kViewerStop);
    headless.wait(kViewerStop);
  }
  unsetenv("DISPLAY");
  if (xvfb) {
    xvfb->signal(SIGTERM);  // a graceful end removes its socket and lock file
    xvfb->wait(kViewerStop);
  }
  const std::string viewer_output = viewer.out() + viewer.err();
  const std::string headless_output = headless.out() + headless.err();
  ASSERT_EQ(pipeline_code, 0) << viewed->out() << viewed->err();
  ASSERT_EQ(viewer_code.value_or(-1), 0) << viewer_output;
  EXPECT_TRUE(fs::exists(dir.path() / "frames.mp4") || fs::exists(dir.path() / "frames_000000.png")) << viewer_output;
  ASSERT_EQ(headless_code.value_or(-1), 0) << headless_output;

  // The pipeline's output does not change with a viewer attached (lockstep is not disturbed).
  EXPECT_EQ(read_file(dir.path() / "viewed.txt"), read_file(dir.path() / "plain.txt"));
  EXPECT_EQ(read_file(dir.path() / "viewed.keyframes.txt"), read_file(dir.path() / "plain.keyframes.txt"));
  ASSERT_EQ(data_rows(dir.path() / "viewed.txt"), 160);

  // The viewer's own counts: every keyframe of the map, one frustum each.
  const auto stats = read_stats(dir.path() / "pictures/viewer_stats.txt");
  ASSERT_FALSE(stats.empty()) << viewer_output;
  const int keyframes = data_rows(dir.path() / "viewed.keyframes.txt");
  ASSERT_GT(keyframes, 5);
  EXPECT_EQ(stats.at("map_keyframes"), std::to_string(keyframes)) << viewer_output;
  EXPECT_EQ(stats.at("frustums_drawn"), std::to_string(keyframes)) << viewer_output;
  EXPECT_GT(std::stoi(stats.at("map_points")), 500) << viewer_output;
  EXPECT_EQ(stats.at("display"), xvfb ? "viz" : "headless") << viewer_output;
  const auto headless_stats = read_stats(dir.path() / "headless/viewer_stats.txt");
  ASSERT_FALSE(headless_stats.empty()) << headless_output;
  EXPECT_EQ(headless_stats.at("display"), "headless");
  EXPECT_EQ(headless_stats.at("frustums_drawn"), std::to_string(keyframes)) << headless_output;
  // The viewer up before the run sees most of its poses (a slow reader may miss some under load); the
  // ground truth covers the whole stretch of the run it saw (one row per frame, so at least one per
  // pose it received).
  const int headless_trajectory = std::stoi(headless_stats.at("trajectory_points"));
  EXPECT_GT(headless_trajectory, 20) << headless_output;
  EXPECT_GE(std::stoi(headless_stats.at("ground_truth_points")), headless_trajectory) << headless_output;
  EXPECT_TRUE(fs::exists(dir.path() / "headless/map_final.png"));

  // The headless viewer's top view is fitted to the trajectory (the default): the estimate and the
  // ground truth under it both show.
  const cv::Mat fitted = cv::imread((dir.path() / "headless/map_final.png").string());
  ASSERT_FALSE(fitted.empty());
  EXPECT_GT(pixels_of(fitted, viewer::colours::kTrajectory), 200);
  EXPECT_GT(pixels_of(fitted, viewer::colours::kGroundTruth), 200);

  // The top view fitted to the map (--fit map): frustums (the only pure-blue pixels) and points on a
  // white background.
  const cv::Mat map = cv::imread((dir.path() / "pictures/map_final.png").string());
  ASSERT_FALSE(map.empty());
  EXPECT_GT(pixels_of(map, viewer::colours::kKeyframe), 10 * keyframes);
  EXPECT_GT(pixels_of(map, viewer::colours::kMapPoint) + pixels_of(map, viewer::colours::kRecentPoint), 500);

  // The 2D view shows the frame it says: its raw half is the dataset image, pixel for pixel. The viewer
  // that joined mid-run may have seen no frame at all on a loaded machine ("none").
  ASSERT_NE(headless_stats.at("frame_seq"), "none") << headless_output;
  expect_frame_view_shows_its_frame(dir.path() / "headless/frame_final.png", dataset, headless_stats.at("frame_seq"));
  if (stats.at("frame_seq") != "none") {
    expect_frame_view_shows_its_frame(dir.path() / "pictures/frame_final.png", dataset, stats.at("frame_seq"));
  }

  if (xvfb) {
    // The viz window's picture: not one flat colour.
    const cv::Mat view_3d = cv::imread((dir.path() / "pictures/map_3d_final.png").string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(view_3d.empty()) << viewer_output;
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(view_3d, &low, &high);
    EXPECT_GT(high - low, 50.0);
  }
  std::printf(
      "[ figures  ] viewer on MH01 (%s): %s frames received, %s drawn, %s dropped before drawing, %s never "
      "received; %d keyframes, %s points; the viewer up before the run: %d trajectory poses\n",
      xvfb ? "Xvfb, viz" : "headless", stats.at("frames_received").c_str(), stats.at("frames_drawn").c_str(),
      stats.at("frames_not_drawn").c_str(), stats.at("frames_missed").c_str(), keyframes,
      stats.at("map_points").c_str(), headless_trajectory);
}

}  // namespace
}  // namespace heslam
