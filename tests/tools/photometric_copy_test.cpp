// heslam-photometric's dataset copy on tiny EuRoC and KITTI folders written by the test: every image
// pixel against its known transformed value, every other file byte for byte, the schedule's blocks,
// the noise identical to the in-memory transform the offline frontend uses, and each error's line
// (with no half-written copy left behind). Plus the CLI's exit codes on bad arguments and input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test_support.hpp"
#include "tiny_euroc_sensor.hpp"
#include "tools/photometric/dataset_copy.hpp"

namespace heslam::photometric {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = test::kTinyEurocWidth;
constexpr int kHeight = test::kTinyEurocHeight;
constexpr int kFrames = 3;

void write_text(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A distinct grey ramp per (frame, side) covering dark and bright levels.
cv::Mat test_image(int index, int side) {
  cv::Mat image(kHeight, kWidth, CV_8UC1);
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u)
      image.at<uchar>(v, u) = static_cast<uchar>((u * 3 + v * 5 + index * 17 + side * 101) % 256);
  return image;
}

const char* const kGroundTruth = "#timestamp,p_x\n100,1.0\n200,2.0\n300,3.0\n";

class PhotometricCopy : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() / ("heslam_photometric_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(root_);
    input_ = root_ / "in";
    output_ = root_ / "out";
    fs::create_directories(input_);
  }
  void TearDown() override { fs::remove_all(root_); }

  void make_euroc() {
    const fs::path mav0 = input_ / "mav0";
    const std::string rows = "#timestamp [ns],filename\n100,100.png\n200,200.png\n300,300.png\n";
    write_text(mav0 / "cam0" / "data.csv", rows);
    write_text(mav0 / "cam1" / "data.csv", rows);
    write_text(mav0 / "cam0" / "sensor.yaml", test::tiny_euroc_sensor_yaml(0.0));
    write_text(mav0 / "cam1" / "sensor.yaml", test::tiny_euroc_sensor_yaml(0.11));
    write_text(mav0 / "state_groundtruth_estimate0" / "data.csv", kGroundTruth);
    for (int k = 0; k < kFrames; ++k) {
      const std::string name = std::to_string(100 * (k + 1)) + ".png";
      fs::create_directories(mav0 / "cam0" / "data");
      fs::create_directories(mav0 / "cam1" / "data");
      cv::imwrite((mav0 / "cam0" / "data" / name).string(), test_image(k, 0));
      cv::imwrite((mav0 / "cam1" / "data" / name).string(), test_image(k, 1));
    }
  }

  void make_kitti() {
    write_text(input_ / "times.txt", "0.0\n0.1\n0.2\n");
    write_text(input_ / "calib.txt",
               "P0: 50.0 0.0 20.0 0.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n"
               "P1: 50.0 0.0 20.0 -27.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n"
               "P2: 50.0 0.0 20.0 0.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n"
               "P3: 50.0 0.0 20.0 0.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n");
    write_text(input_ / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
    for (int k = 0; k < kFrames; ++k) {
      char name[16];
      std::snprintf(name, sizeof(name), "%06d.png", k);
      fs::create_directories(input_ / "image_0");
      fs::create_directories(input_ / "image_1");
      cv::imwrite((input_ / "image_0" / name).string(), test_image(k, 0));
      cv::imwrite((input_ / "image_1" / name).string(), test_image(k, 1));
    }
  }

  std::string copy_error(const DatasetCopyOptions& options) {
    try {
      write_dataset_copy(input_, output_, options);
    } catch (const std::runtime_error& error) {
      return error.what();
    }
    return "(no error)";
  }

  fs::path root_;
  fs::path input_;
  fs::path output_;
};

cv::Mat read_grey(const fs::path& path) { return cv::imread(path.string(), cv::IMREAD_GRAYSCALE); }

// Every pixel of `transformed` is expected(pixel of `original`).
template <typename Expected>
int pixels_off(const cv::Mat& original, const cv::Mat& transformed, Expected expected) {
  if (original.size() != transformed.size()) return static_cast<int>(original.total());
  int off = 0;
  for (int v = 0; v < original.rows; ++v)
    for (int u = 0; u < original.cols; ++u)
      off += transformed.at<uchar>(v, u) != expected(original.at<uchar>(v, u)) ? 1 : 0;
  return off;
}

TEST_F(PhotometricCopy, EurocGainsTransformEveryPixelAndKeepOtherFiles) {
  make_euroc();
  DatasetCopyOptions options;
  options.stereo_gain = {{0.4, 2.0}};  // x0.4 never lands on a half, so the rounding is unambiguous
  const DatasetCopySummary summary = write_dataset_copy(input_, output_, options);
  EXPECT_EQ(summary.format, DatasetFormat::kEuroc);
  EXPECT_EQ(summary.frames, 3u);
  EXPECT_EQ(summary.copied_files, 5u);  // two data.csv, two sensor.yaml, the ground truth
  EXPECT_EQ(summary.left_saturated_share, 0.0);
  EXPECT_GT(summary.right_saturated_share, 0.3);  // grey >= 128 clips at x2
  for (const char* file : {"mav0/cam0/data.csv", "mav0/cam1/data.csv", "mav0/cam0/sensor.yaml", "mav0/cam1/sensor.yaml",
                           "mav0/state_groundtruth_estimate0/data.csv"}) {
    EXPECT_EQ(read_bytes(output_ / file), read_bytes(input_ / file)) << file;
  }
  for (int k = 0; k < kFrames; ++k) {
    const std::string name = std::to_string(100 * (k + 1)) + ".png";
    const cv::Mat left = read_grey(output_ / "mav0" / "cam0" / "data" / name);
    const cv::Mat right = read_grey(output_ / "mav0" / "cam1" / "data" / name);
    EXPECT_EQ(pixels_off(test_image(k, 0), left, [](int g) { return static_cast<int>(std::lround(g * 0.4)); }), 0)
        << name;
    EXPECT_EQ(pixels_off(test_image(k, 1), right, [](int g) { return std::min(255, 2 * g); }), 0) << name;
  }
  // Spot values by hand: frame 0 left (0,0) = 0, (1,0) = 3 x 0.4 -> 1; right (0,0) = 101 x 2 = 202, (27,0) = 182 ->
  // 255.
  const cv::Mat left0 = read_grey(output_ / "mav0" / "cam0" / "data" / "100.png");
  const cv::Mat right0 = read_grey(output_ / "mav0" / "cam1" / "data" / "100.png");
  EXPECT_EQ(left0.at<uchar>(0, 1), 1);
  EXPECT_EQ(right0.at<uchar>(0, 0), 202);
  EXPECT_EQ(right0.at<uchar>(0, 27), 255);
  // The copy is a dataset of the same frames.
  const StereoDataset copy = open_dataset(output_);
  ASSERT_EQ(copy.frames.size(), 3u);
  EXPECT_EQ(copy.frames[2].stamp_ns, 300);
}

TEST_F(PhotometricCopy, ScheduleGivesEachBlockOfFramesItsGains) {
  make_euroc();
  DatasetCopyOptions options;
  options.stereo_gain = parse_stereo_gain_schedule("1,1/1,2/1,4");
  write_dataset_copy(input_, output_, options);
  const int factor[kFrames] = {1, 2, 4};
  for (int k = 0; k < kFrames; ++k) {
    const std::string name = std::to_string(100 * (k + 1)) + ".png";
    const int f = factor[k];
    EXPECT_EQ(
        pixels_off(test_image(k, 0), read_grey(output_ / "mav0" / "cam0" / "data" / name), [](int g) { return g; }), 0);
    EXPECT_EQ(pixels_off(test_image(k, 1), read_grey(output_ / "mav0" / "cam1" / "data" / name),
                         [f](int g) { return std::min(255, f * g); }),
              0)
        << name;
  }
}

TEST_F(PhotometricCopy, KittiLowContrastAndDarkMatchTheInMemoryTransform) {
  make_kitti();
  DatasetCopyOptions options;
  options.variant = PhotometricVariant::kLowContrast;
  const DatasetCopySummary summary = write_dataset_copy(input_, output_, options);
  EXPECT_EQ(summary.format, DatasetFormat::kKitti);
  EXPECT_EQ(summary.copied_files, 3u);  // times.txt, calib.txt, poses.txt
  EXPECT_EQ(read_bytes(output_ / "poses.txt"), read_bytes(input_ / "poses.txt"));
  // x0.12 around mid grey: 0 -> round(112.64) = 113, 255 -> round(143.24) = 143.
  const cv::Mat left0 = read_grey(output_ / "image_0" / "000000.png");
  EXPECT_EQ(left0.at<uchar>(0, 0), 113);
  double min_grey = 0.0;
  double max_grey = 0.0;
  cv::minMaxLoc(left0, &min_grey, &max_grey);
  EXPECT_GE(min_grey, 113.0);
  EXPECT_LE(max_grey, 143.0);

  // Dark: noisy, so compared with apply_to_pair on the same frame index (what the offline frontend does).
  const fs::path dark = root_ / "dark";
  options.variant = PhotometricVariant::kDark;
  options.stereo_gain = {{1.0, 3.0}};
  write_dataset_copy(input_, dark, options);
  for (int k = 0; k < kFrames; ++k) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.png", k);
    cv::Mat left = test_image(k, 0);
    cv::Mat right = test_image(k, 1);
    apply_to_pair(left, right, PhotometricVariant::kDark, {1.0, 3.0}, static_cast<std::uint64_t>(k));
    EXPECT_EQ(cv::norm(left, read_grey(dark / "image_0" / name), cv::NORM_INF), 0.0) << name;
    EXPECT_EQ(cv::norm(right, read_grey(dark / "image_1" / name), cv::NORM_INF), 0.0) << name;
    EXPECT_GT(cv::norm(left, read_grey(dark / "image_1" / name), cv::NORM_INF), 0.0);  // the sides differ
  }
}

TEST_F(PhotometricCopy, ErrorsNameTheFileAndLeaveNoHalfCopy) {
  DatasetCopyOptions options;
  options.stereo_gain = {{0.5, 1.5}};
  // Not a dataset.
  EXPECT_NE(copy_error(options).find("no EuRoC (mav0/cam0/data.csv) or KITTI"), std::string::npos)
      << copy_error(options);
  EXPECT_FALSE(fs::exists(output_));

  make_euroc();
  // Output already holds something: refused, untouched.
  write_text(output_ / "keep.txt", "mine");
  EXPECT_NE(copy_error(options).find("exists and is not an empty folder"), std::string::npos);
  EXPECT_EQ(read_bytes(output_ / "keep.txt"), "mine");
  fs::remove_all(output_);

  // Output inside the input.
  const fs::path inside = input_ / "copy";
  std::string error = "(no error)";
  try {
    write_dataset_copy(input_, inside, options);
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  EXPECT_NE(error.find("must not be (inside) the input folder"), std::string::npos) << error;

  // A listed image that is not an image: the error names it, the half-written copy is removed.
  const fs::path broken = input_ / "mav0" / "cam1" / "data" / "200.png";
  write_text(broken, "not a png");
  error = copy_error(options);
  EXPECT_NE(error.find("200.png: cannot read the image"), std::string::npos) << error;
  EXPECT_FALSE(fs::exists(output_));
}

TEST(PhotometricCli, UsageErrorsExitTwoAndABadInputExitsOne) {
  const std::string tool = (test::bin_dir() / "heslam-photometric").string();
  const auto exit_code = [](const std::string& command) {
    const int status = std::system((command + " >/dev/null 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  EXPECT_EQ(exit_code(tool + " in out"), 2);                    // nothing to do
  EXPECT_EQ(exit_code(tool + " in out --stereo-gain 0.5"), 2);  // not L,R
  EXPECT_EQ(exit_code(tool + " in out --variant bright"), 2);   // unknown variant
  EXPECT_EQ(exit_code(tool + " in --stereo-gain 1,2"), 2);      // no output
  const test::ScratchDir scratch("photometric_cli");
  EXPECT_EQ(exit_code(tool + " " + scratch.path().string() + "/missing " + scratch.path().string() +
                      "/out --stereo-gain 1,2"),
            1);  // the input is no dataset
}

}  // namespace
}  // namespace heslam::photometric
