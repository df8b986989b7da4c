// Output layouts: EuRoC files readable by cv::FileStorage (and plain YAML), KITTI calib/poses/times in
// the dataset's format, and synth.yaml listing every event with its time range.
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "synth_test_util.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> lines(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

std::vector<double> numbers(const std::string& line) {
  std::istringstream ss(line);
  std::vector<double> v;
  for (double x; ss >> x;) v.push_back(x);
  return v;
}

TEST(SynthOutput, EurocLayoutAndMetadata) {
  const fs::path dir = fs::temp_directory_path() / "heslam_synth_euroc_test";
  fs::remove_all(dir);
  Preset preset = test::repo_preset("room_exposure");
  preset.frames = 3;
  ExposureEvent stereo_gain;
  stereo_gain.kind = EventKind::kStereoGain;
  stereo_gain.start_s = 2.0;
  stereo_gain.end_s = 4.0;
  stereo_gain.left = 0.35;
  stereo_gain.right = 2.0;
  preset.events.push_back(stereo_gain);
  SequenceRenderer renderer(preset, {.seed = 4});
  write_sequence(renderer, OutputFormat::kEuroc, dir);

  for (const char* cam : {"cam0", "cam1"}) {
    const auto csv = lines(dir / "mav0" / cam / "data.csv");
    ASSERT_EQ(csv.size(), 4u);
    EXPECT_EQ(csv[0], "#timestamp [ns],filename");
    EXPECT_EQ(csv[1], "1600000000000000000,1600000000000000000.png");
    EXPECT_EQ(csv[2], "1600000000050000000,1600000000050000000.png");
    const cv::Mat img =
        cv::imread((dir / "mav0" / cam / "data" / "1600000000050000000.png").string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(img.type(), CV_8UC1);
    EXPECT_EQ(img.cols, 752);
    EXPECT_EQ(img.rows, 480);
    cv::FileStorage fs((dir / "mav0" / cam / "sensor.yaml").string(), cv::FileStorage::READ);
    ASSERT_TRUE(fs.isOpened());
    std::vector<double> intr, dist, T;
    std::vector<int> res;
    fs["intrinsics"] >> intr;
    fs["distortion_coefficients"] >> dist;
    fs["resolution"] >> res;
    fs["T_BS"]["data"] >> T;
    EXPECT_EQ(static_cast<std::string>(fs["distortion_model"]), "radial-tangential");
    EXPECT_EQ(static_cast<std::string>(fs["camera_model"]), "pinhole");
    EXPECT_EQ(static_cast<int>(fs["rate_hz"]), 20);
    ASSERT_EQ(intr.size(), 4u);
    EXPECT_DOUBLE_EQ(intr[0], 458.654);
    ASSERT_EQ(dist.size(), 4u);
    EXPECT_DOUBLE_EQ(dist[0], -0.28340811);
    EXPECT_EQ(res, (std::vector<int>{752, 480}));
    ASSERT_EQ(T.size(), 16u);
  }
  // The two T_BS differ by the baseline along the left camera's x axis.
  const Pose3 T_rl = renderer.T_BS_right().inverse() * renderer.T_BS_left();
  EXPECT_NEAR(T_rl.translation().x(), -0.11, 1e-12);

  const auto gt = lines(dir / "mav0" / "state_groundtruth_estimate0" / "data.csv");
  ASSERT_EQ(gt.size(), 4u);
  EXPECT_EQ(std::count(gt[1].begin(), gt[1].end(), ','), 16) << "EuRoC 17-column ground truth";
  EXPECT_EQ(lines(dir / "timestamps.txt").front(), "1600000000000000000");

  cv::FileStorage meta((dir / "synth.yaml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(meta.isOpened());
  EXPECT_EQ(static_cast<std::string>(meta["preset"]), "room_exposure");
  EXPECT_EQ(static_cast<int>(meta["seed"]), 4);
  const cv::FileNode events = meta["events"];
  ASSERT_EQ(events.size(), preset.events.size());
  for (std::size_t i = 0; i < preset.events.size(); ++i) {
    const cv::FileNode e = events[static_cast<int>(i)];
    EXPECT_EQ(static_cast<std::string>(e["type"]), to_string(preset.events[i].kind));
    EXPECT_DOUBLE_EQ(static_cast<double>(e["start_s"]), preset.events[i].start_s);
    EXPECT_DOUBLE_EQ(static_cast<double>(e["end_s"]), preset.events[i].end_s);
  }
  EXPECT_EQ(static_cast<std::string>(events[4]["type"]), "stereo_gain");
  EXPECT_DOUBLE_EQ(static_cast<double>(events[4]["left"]), 0.35);
  EXPECT_DOUBLE_EQ(static_cast<double>(events[4]["right"]), 2.0);
  cv::FileStorage settings((dir / "orbslam2_settings.yaml").string(), cv::FileStorage::READ);
  ASSERT_TRUE(settings.isOpened());
  cv::Mat P_right;
  settings["RIGHT.P"] >> P_right;
  ASSERT_EQ(P_right.rows, 3);
  EXPECT_NEAR(-P_right.at<double>(0, 3) / P_right.at<double>(0, 0), 0.11, 1e-9) << "baseline from the rectified P";
  EXPECT_NEAR(static_cast<double>(settings["Camera.bf"]) / static_cast<double>(settings["Camera.fx"]), 0.11, 1e-9);
  fs::remove_all(dir);
}

TEST(SynthOutput, KittiLayout) {
  const fs::path dir = fs::temp_directory_path() / "heslam_synth_kitti_test";
  fs::remove_all(dir);
  Preset preset = test::repo_preset("street");
  SequenceRenderer renderer(preset, {.seed = 4, .frames = 3, .apply_distortion = false});
  write_sequence(renderer, OutputFormat::kKitti, dir);
  const auto calib = lines(dir / "calib.txt");
  ASSERT_EQ(calib.size(), 5u);
  ASSERT_EQ(calib[1].rfind("P1: ", 0), 0u);
  const auto p1 = numbers(calib[1].substr(4));
  ASSERT_EQ(p1.size(), 12u);
  EXPECT_NEAR(-p1[3] / p1[0], 0.54, 1e-9) << "KITTI P1 holds -fx * baseline";
  EXPECT_DOUBLE_EQ(p1[0], 718.856);
  const auto times = lines(dir / "times.txt");
  ASSERT_EQ(times.size(), 3u);
  EXPECT_NEAR(std::stod(times[2]), 0.2, 1e-9);
  const auto poses = lines(dir / "poses.txt");
  ASSERT_EQ(poses.size(), 3u);
  const auto first = numbers(poses[0]);
  ASSERT_EQ(first.size(), 12u);
  EXPECT_NEAR(first[0], 1.0, 1e-9);
  EXPECT_NEAR(first[3], 0.0, 1e-9);
  // Driving forward: the camera moves along its own +z.
  EXPECT_GT(numbers(poses[2])[11], 0.0);
  const cv::Mat img = cv::imread((dir / "image_1" / "000002.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(img.cols, 1241);
  EXPECT_EQ(img.rows, 376);
  fs::remove_all(dir);
}

TEST(SynthOutput, KittiRefusesDistortedImages) {
  SequenceRenderer renderer(test::repo_preset("room"), {.frames = 1});
  ASSERT_TRUE(renderer.distortion_applied());
  EXPECT_THROW(write_sequence(renderer, OutputFormat::kKitti, fs::temp_directory_path() / "heslam_synth_never"),
               std::runtime_error);
}

}  // namespace
}  // namespace heslam::synth
