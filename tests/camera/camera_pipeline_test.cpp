// heslam-camera as a process: the MH01 clip as a side-by-side video (FFV1, lossless) and as a
// side-by-side image folder through config/pipelines/camera_realtime.yaml (every published frame has
// a pose or is counted lost; stamps are the clip's), and the bad inputs, each with its exit code and
// last line: a missing device, the end of a recording standing for an unplugged camera (alone and
// under the supervisor), a wrong resolution, an odd side-by-side width, stamps going backwards.
// Real time: no assertion depends on speed (how many frames the frontend missed varies with load).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "child_process.hpp"
#include "pipeline_runs.hpp"
#include "test_support.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr const char* kClip = "euroc_mh01_handheld";
constexpr int kClipFrames = 160;
constexpr std::int64_t kFirstStampNs = 1403636584763555584;
// Bounds of a hung process, not performance assertions.
constexpr auto kCameraBound = std::chrono::seconds(60);

fs::path mav0() { return test::shared_dataset(kClip) / "mav0"; }

// cam0/data.csv's stamps, in order.
std::vector<std::int64_t> clip_stamps() {
  std::ifstream csv(mav0() / "cam0/data.csv");
  std::vector<std::int64_t> stamps;
  for (std::string line; std::getline(csv, line);) {
    if (!line.empty() && line[0] != '#') stamps.push_back(std::stoll(line.substr(0, line.find(','))));
  }
  return stamps;
}

cv::Mat side_by_side(std::int64_t stamp) {
  const std::string name = std::to_string(stamp) + ".png";
  cv::Mat both;
  cv::hconcat(cv::imread((mav0() / "cam0/data" / name).string(), cv::IMREAD_GRAYSCALE),
              cv::imread((mav0() / "cam1/data" / name).string(), cv::IMREAD_GRAYSCALE), both);
  return both;
}

// The first `frames` pairs of the clip as a side-by-side FFV1 video at 20 fps, made once per build
// tree (renamed into place only when complete); empty when this OpenCV cannot write FFV1.
fs::path clip_video(int frames) {
  const fs::path video =
      test::bin_dir().parent_path() / "test_data" / ("camera_mh01_sbs_" + std::to_string(frames) + ".avi");
  if (fs::exists(video)) return video;
  fs::create_directories(video.parent_path());
  const fs::path partial = video.string() + ".partial." + std::to_string(getpid()) + ".avi";
  {
    const std::vector<std::int64_t> stamps = clip_stamps();
    cv::VideoWriter writer(partial.string(), cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 20.0, cv::Size(1504, 480),
                           false);
    if (!writer.isOpened()) return {};
    for (int i = 0; i < frames; ++i) writer.write(side_by_side(stamps[static_cast<std::size_t>(i)]));
  }
  fs::rename(partial, video);
  return video;
}

// The clip as a folder of side-by-side PNGs with a data.csv of the clip's stamps.
fs::path clip_folder(const fs::path& dir) {
  const fs::path folder = dir / "sbs";
  fs::create_directories(folder / "data");
  std::ofstream csv(folder / "data.csv");
  csv << "#timestamp [ns],filename\n";
  for (const std::int64_t stamp : clip_stamps()) {
    const std::string name = std::to_string(stamp) + ".png";
    cv::imwrite((folder / "data" / name).string(), side_by_side(stamp));
    csv << stamp << "," << name << "\n";
  }
  return folder;
}

std::unique_ptr<test::ChildProcess> start_camera_pipeline(const fs::path& dir, const std::string& label,
                                                          const std::vector<std::string>& pipeline_args) {
  std::vector<std::string> args{(test::source_dir() / "config/pipelines/camera_realtime.yaml").string(),
                                "--domain",
                                std::to_string(test::exclusive_domain_id()),
                                "--log-dir",
                                (dir / ("logs_" + label)).string(),
                                "--arg",
                                "calibration=" + mav0().string(),
                                "--arg",
                                "output=" + (dir / (label + ".txt")).string()};
  for (const std::string& arg : pipeline_args) args.insert(args.end(), {"--arg", arg});
  return std::make_unique<test::ChildProcess>(test::bin_dir() / "heslam-supervisor", args, dir, "supervisor_" + label);
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

// The supervisor's last line for a recording played to its end: every pair of the clip was published
// or counted dropped, every published frame has a pose or is counted lost (untracked or missed).
void expect_every_frame_accounted(const test::ChildProcess& supervisor, const fs::path& trajectory,
                                  double stamp_tolerance_s) {
  const std::string last = test::last_line(supervisor.out() + supervisor.err());
  const std::regex verdict(
      std::string(
          R"(pipeline finished: tracked (\d+)/(\d+) frames, (\d+) lost, trajectory .*; (\d+) frames published, )") +
      R"((\d+) dropped, 0 unpaired \(0 left, 0 right\), 0 with stamps going backwards, 0 unreadable images; )" +
      R"(CPU [0-9.]+ ms per frame)");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(last, match, verdict)) << last;
  const int tracked = std::stoi(match[1]);
  const int accounted = std::stoi(match[2]);
  const int lost = std::stoi(match[3]);
  const int published = std::stoi(match[4]);
  const int dropped = std::stoi(match[5]);
  // Every pair of the clip was published or counted dropped by the camera (a pair captured while the
  // previous one was still being published: load-dependent, so not asserted to be 0).
  EXPECT_EQ(published + dropped, kClipFrames);
  EXPECT_EQ(accounted, published);
  EXPECT_EQ(tracked + lost, published);
  EXPECT_GT(tracked, 0);
  const eval::Trajectory poses = eval::read_trajectory(trajectory);
  EXPECT_EQ(poses.stamps_s.size(), static_cast<std::size_t>(tracked));
  // Each pose is stamped with one of the clip's frames (the video: first stamp + 50 ms steps, which
  // the clip's hardware stamps follow to well under a millisecond).
  const std::vector<std::int64_t> stamps = clip_stamps();
  for (const double stamp_s : poses.stamps_s) {
    double nearest = 1e9;
    for (const std::int64_t clip_ns : stamps) nearest = std::min(nearest, std::abs(stamp_s - clip_ns * 1e-9));
    EXPECT_LE(nearest, stamp_tolerance_s) << "pose at " << stamp_s;
  }
}

TEST(CameraPipeline, Mh01SideBySideVideoEveryFrameHasAPoseOrIsCountedLost) {
  HESLAM_REQUIRE_SHARED_DATA(kClip);
  const fs::path video = clip_video(kClipFrames);
  if (video.empty()) GTEST_SKIP() << "this OpenCV cannot write FFV1 video";
  const test::ScratchDir dir("camera_pipeline_video");
  auto supervisor = start_camera_pipeline(
      dir.path(), "video",
      {"source=" + video.string(), "layout=side-by-side", "first_stamp_ns=" + std::to_string(kFirstStampNs)});
  ASSERT_EQ(test::finish(*supervisor), 0) << supervisor->err() << supervisor->out();
  expect_every_frame_accounted(*supervisor, dir.path() / "video.txt", 1e-3);
  // FFmpeg hands grey FFV1 over as BGR: converted, and said once.
  EXPECT_EQ(occurrences(supervisor->out() + supervisor->err(), "delivers 3-channel images: converted to mono8"), 1u);
}

TEST(CameraPipeline, Mh01SideBySideFolderKeepsTheClipStamps) {
  HESLAM_REQUIRE_SHARED_DATA(kClip);
  const test::ScratchDir dir("camera_pipeline_folder");
  const fs::path folder = clip_folder(dir.path());
  auto supervisor = start_camera_pipeline(dir.path(), "folder", {"source=" + folder.string(), "layout=side-by-side"});
  ASSERT_EQ(test::finish(*supervisor), 0) << supervisor->err() << supervisor->out();
  expect_every_frame_accounted(*supervisor, dir.path() / "folder.txt", 1e-6);
}

TEST(CameraPipeline, RecordingEndingAsALostCameraFailsTheRunAndSaysSo) {
  HESLAM_REQUIRE_SHARED_DATA(kClip);
  const fs::path video = clip_video(40);
  if (video.empty()) GTEST_SKIP() << "this OpenCV cannot write FFV1 video";
  const test::ScratchDir dir("camera_pipeline_unplugged");
  auto supervisor =
      start_camera_pipeline(dir.path(), "unplugged", {"source=" + video.string(), "layout=side-by-side", "end=fail"});
  EXPECT_EQ(test::finish(*supervisor), 1) << supervisor->err() << supervisor->out();
  const std::string last = test::last_line(supervisor->out() + supervisor->err());
  EXPECT_NE(last.find("pipeline failed: camera"), std::string::npos) << last;
  EXPECT_NE(last.find("source ended abnormally: end of " + video.string() +
                      " after 40 frames (--end fail: the end of the recording stands for a lost camera)"),
            std::string::npos)
      << last;
}

struct CameraRun {
  int exit_code = -1;
  std::string last;
};

// heslam-camera alone on the test's domain (no subscriber needed: --wait 0).
CameraRun run_camera(const fs::path& dir, const std::string& label, std::vector<std::string> args) {
  args.insert(args.end(), {"--domain", std::to_string(test::exclusive_domain_id()), "--wait", "0"});
  test::ChildProcess camera(test::bin_dir() / "heslam-camera", args, dir, label);
  CameraRun run;
  run.exit_code = camera.wait(kCameraBound).value_or(-1);
  run.last = test::last_line(camera.err());
  return run;
}

TEST(CameraProcess, BadInputsEndWithOneLineAndTheirExitCode) {
  HESLAM_REQUIRE_SHARED_DATA(kClip);
  const test::ScratchDir dir("camera_bad_inputs");
  const std::string calibration = mav0().string();

  CameraRun run = run_camera(dir.path(), "missing", {"/dev/heslam-no-camera", "--calibration", calibration});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(run.last, "heslam-camera: camera /dev/heslam-no-camera: cannot open the V4L2 device (no such device)");

  // A folder of 3 frames: side-by-side halves of 640x480, not the calibration's 752x480.
  const fs::path small = dir.path() / "small";
  fs::create_directories(small);
  for (int i = 0; i < 3; ++i) {
    cv::imwrite((small / (std::to_string(i) + ".png")).string(), cv::Mat(480, 1280, CV_8UC1, cv::Scalar(i)));
  }
  run =
      run_camera(dir.path(), "resolution", {small.string(), "--calibration", calibration, "--layout", "side-by-side"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.last.find("error: source failed: wrong resolution: " + small.string() +
                          " delivers 640x480 images per camera (each half), the calibration"),
            std::string::npos)
      << run.last;
  EXPECT_NE(run.last.find("is for 752x480; 0 frames published"), std::string::npos) << run.last;

  const fs::path odd = dir.path() / "odd";
  fs::create_directories(odd);
  cv::imwrite((odd / "0.png").string(), cv::Mat(480, 1505, CV_8UC1, cv::Scalar(0)));
  run = run_camera(dir.path(), "odd", {odd.string(), "--calibration", calibration, "--layout", "side-by-side"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.last.find("error: source failed: " + odd.string() +
                          ": side-by-side frame is 1505 px wide (odd): it cannot be two images of one size"),
            std::string::npos)
      << run.last;

  // Stamps going backwards: the clip's first 4 pairs with rows 2 and 3 swapped in data.csv.
  const fs::path swapped = dir.path() / "swapped";
  fs::create_directories(swapped / "data");
  {
    const std::vector<std::int64_t> stamps = clip_stamps();
    std::ofstream csv(swapped / "data.csv");
    for (const int i : {0, 1, 3, 2}) {
      const std::string name = std::to_string(stamps[static_cast<std::size_t>(i)]) + ".png";
      cv::imwrite((swapped / "data" / name).string(), side_by_side(stamps[static_cast<std::size_t>(i)]));
      csv << stamps[static_cast<std::size_t>(i)] << "," << name << "\n";
    }
  }
  run =
      run_camera(dir.path(), "backwards", {swapped.string(), "--calibration", calibration, "--layout", "side-by-side"});
  EXPECT_EQ(run.exit_code, 0);
  std::smatch match;
  ASSERT_TRUE(std::regex_search(
      run.last, match,
      std::regex(
          R"((\d+) frames published, (\d+) dropped, 0 unpaired \(0 left, 0 right\), 1 with stamps going backwards)")))
      << run.last;
  EXPECT_EQ(std::stoi(match[1]) + std::stoi(match[2]), 3);  // drops depend on the load: counted, not asserted

  // The end of a recording as an unplugged camera, without a supervisor.
  run = run_camera(dir.path(), "end", {swapped.string(), "--calibration", calibration, "--end", "fail"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.last.find("error: source ended abnormally: end of " + swapped.string() + " after 4 images"),
            std::string::npos)
      << run.last;
}

}  // namespace
}  // namespace heslam
