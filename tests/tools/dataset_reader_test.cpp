// heslam_dataset on tiny EuRoC and KITTI folders written by the test (known answers for every field
// and every error line), ground truth paired with frames by stamp, plus the real EuRoC clip from the
// shared data when present.
#include <cstdio>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "test_support.hpp"
#include "tiny_euroc_sensor.hpp"
#include "tools/dataset/ground_truth.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/dataset/stereo_images.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = test::kTinyEurocWidth;
constexpr int kHeight = test::kTinyEurocHeight;

void write_text(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// A distinct, reproducible grey image per (index, side) so a mix-up of files would be seen.
cv::Mat test_image(int index, int side) {
  cv::Mat image(kHeight, kWidth, CV_8UC1);
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u)
      image.at<uchar>(v, u) = static_cast<uchar>(u * 3 + v * 5 + index * 17 + side * 101);
  return image;
}

class DatasetReader : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() / ("heslam_dataset_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // An EuRoC folder with the given csv bodies (rows "stamp,file"); images written for listed rows.
  void make_euroc(const std::string& left_rows, const std::string& right_rows, bool write_images = true) {
    const fs::path mav0 = root_ / "mav0";
    write_text(mav0 / "cam0" / "data.csv", "#timestamp [ns],filename\n" + left_rows);
    write_text(mav0 / "cam1" / "data.csv", "#timestamp [ns],filename\n" + right_rows);
    write_text(mav0 / "cam0" / "sensor.yaml", test::tiny_euroc_sensor_yaml(0.0));
    write_text(mav0 / "cam1" / "sensor.yaml", test::tiny_euroc_sensor_yaml(0.11));
    fs::create_directories(mav0 / "cam0" / "data");
    fs::create_directories(mav0 / "cam1" / "data");
    if (!write_images) return;
    int index = 0;
    for (const std::string stamp : {"100", "200", "300"}) {
      cv::imwrite((mav0 / "cam0" / "data" / (stamp + ".png")).string(), test_image(index, 0));
      cv::imwrite((mav0 / "cam1" / "data" / (stamp + ".png")).string(), test_image(index, 1));
      ++index;
    }
  }

  void make_kitti(const std::string& times) {
    write_text(root_ / "times.txt", times);
    write_text(root_ / "calib.txt",
               "P0: 50.0 0.0 20.0 0.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n"
               "P1: 50.0 0.0 20.0 -27.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n"
               "P2: 50.0 0.0 20.0 0.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n"
               "P3: 50.0 0.0 20.0 0.0 0.0 50.0 15.0 0.0 0.0 0.0 1.0 0.0\n");
    fs::create_directories(root_ / "image_0");
    fs::create_directories(root_ / "image_1");
    for (int i = 0; i < 3; ++i) {
      char name[16];
      std::snprintf(name, sizeof(name), "%06d.png", i);
      cv::imwrite((root_ / "image_0" / name).string(), test_image(i, 0));
      cv::imwrite((root_ / "image_1" / name).string(), test_image(i, 1));
    }
  }

  std::string open_error(const DatasetOptions& options = {}) {
    try {
      open_dataset(root_, options);
    } catch (const std::runtime_error& error) {
      return error.what();
    }
    return "(no error)";
  }

  fs::path root_;
};

const std::string kThreeRows = "100,100.png\n200,200.png\n300,300.png\n";

// The error loading a frame's images gives, or "(no error)".
std::string error_of(const StereoFrameFiles& frame) {
  try {
    load_stereo_images(frame);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST_F(DatasetReader, EurocPairsRowsAndReadsCalibration) {
  make_euroc(kThreeRows, kThreeRows);
  const StereoDataset dataset = open_dataset(root_);
  EXPECT_EQ(dataset.format, DatasetFormat::kEuroc);
  ASSERT_EQ(dataset.frames.size(), 3u);
  EXPECT_EQ(dataset.frames[1].stamp_ns, 200);
  EXPECT_EQ(dataset.frames[1].left, root_ / "mav0" / "cam0" / "data" / "200.png");
  EXPECT_EQ(dataset.frames[1].right, root_ / "mav0" / "cam1" / "data" / "200.png");
  EXPECT_EQ(dataset.skipped_rows, 0);
  EXPECT_DOUBLE_EQ(dataset.calibration.left.fx_px, 50.0);
  EXPECT_EQ(dataset.calibration.left.width_px, kWidth);
  EXPECT_NEAR(dataset.calibration.T_rl().translation().x(), -0.11, 1e-12);
  // Naming mav0/ itself works too.
  EXPECT_EQ(open_dataset(root_ / "mav0").frames.size(), 3u);
}

TEST_F(DatasetReader, EurocUnpairedRowIsSkippedAndCountedOrFatalWhenStrict) {
  make_euroc(kThreeRows, kThreeRows + "400,400.png\n");
  const StereoDataset dataset = open_dataset(root_);
  EXPECT_EQ(dataset.frames.size(), 3u);
  EXPECT_EQ(dataset.skipped_rows, 1);
  ASSERT_EQ(dataset.warnings.size(), 1u);
  EXPECT_NE(dataset.warnings[0].find("cam1/data.csv line 5: stamp 400 has no cam0 frame"), std::string::npos)
      << dataset.warnings[0];
  DatasetOptions strict;
  strict.strict = true;
  EXPECT_NE(open_error(strict).find("cam1/data.csv line 5: stamp 400 has no cam0 frame"), std::string::npos);
}

TEST_F(DatasetReader, EurocLeftRightStampMismatch) {
  make_euroc(kThreeRows, "150,100.png\n250,200.png\n350,300.png\n");
  DatasetOptions options;
  options.max_stereo_offset_ns = 10;
  EXPECT_NE(open_error(options).find("no cam0 stamp matches a cam1 stamp (left/right stamp mismatch)"),
            std::string::npos);
  options.max_stereo_offset_ns = 50;  // within tolerance: paired, stamped with the left stamp
  const StereoDataset dataset = open_dataset(root_, options);
  ASSERT_EQ(dataset.frames.size(), 3u);
  EXPECT_EQ(dataset.frames[0].stamp_ns, 100);
}

TEST_F(DatasetReader, EurocNonIncreasingStamps) {
  make_euroc("100,100.png\n300,300.png\n200,200.png\n", kThreeRows);
  EXPECT_NE(open_error().find("cam0/data.csv line 4: stamp 200 is not after the previous stamp 300"), std::string::npos)
      << open_error();
}

TEST_F(DatasetReader, EurocMalformedRow) {
  make_euroc("100,100.png\nabc,200.png\n", kThreeRows);
  EXPECT_NE(open_error().find("cam0/data.csv line 3: expected '<timestamp ns>,<file name>', got 'abc,200.png'"),
            std::string::npos)
      << open_error();
}

TEST_F(DatasetReader, EurocEmptyFrameList) {
  make_euroc("", kThreeRows);
  EXPECT_NE(open_error().find("cam0/data.csv: no frames listed (empty recording)"), std::string::npos) << open_error();
}

TEST_F(DatasetReader, EurocUnreadableCalibrationNamesTheFile) {
  make_euroc(kThreeRows, kThreeRows);
  fs::remove(root_ / "mav0" / "cam1" / "sensor.yaml");
  EXPECT_NE(open_error().find("sensor.yaml"), std::string::npos) << open_error();
}

// --camera FILE of the replay: the calibration is a settings file's instead of the dataset's, for both
// layouts; a bad file is the loader's one line naming it.
TEST_F(DatasetReader, CalibrationFromASettingsFileReplacesTheDatasets) {
  const fs::path settings = root_ / "rig.yaml";
  write_text(settings,
             "%YAML:1.0\nFile.version: \"1.0\"\nCamera.type: \"PinHole\"\nCamera1.fx: 50.0\nCamera1.fy: 50.0\n"
             "Camera1.cx: 20.0\nCamera1.cy: 15.0\nCamera.width: " +
                 std::to_string(kWidth) + "\nCamera.height: " + std::to_string(kHeight) + "\nStereo.b: 0.3\n");
  make_euroc(kThreeRows, kThreeRows);
  DatasetOptions options;
  options.calibration_file = settings;
  const StereoDataset euroc = open_dataset(root_, options);
  EXPECT_EQ(euroc.calibration.source, settings.string());
  EXPECT_TRUE(euroc.calibration.input_rectified);
  EXPECT_NEAR(euroc.calibration.T_rl().translation().norm(), 0.3, 1e-12);
  EXPECT_EQ(euroc.frames.size(), 3u);

  fs::remove_all(root_ / "mav0");
  make_kitti("0.0\n0.1\n0.2\n");
  const StereoDataset kitti = open_dataset(root_, options);
  EXPECT_EQ(kitti.calibration.source, settings.string());
  EXPECT_NEAR(kitti.calibration.left.fx_px, 50.0, 1e-12);

  options.calibration_file = root_ / "missing.yaml";
  EXPECT_NE(open_error(options).find("missing.yaml"), std::string::npos) << open_error(options);
}

TEST_F(DatasetReader, FrameListsWithoutCalibration) {
  make_euroc(kThreeRows, kThreeRows);
  fs::remove(root_ / "mav0" / "cam1" / "sensor.yaml");  // not read
  DatasetOptions lists_only;
  lists_only.load_calibration = false;
  const StereoDataset dataset = open_dataset(root_, lists_only);
  ASSERT_EQ(dataset.frames.size(), 3u);
  EXPECT_EQ(dataset.frames[2].right, root_ / "mav0" / "cam1" / "data" / "300.png");
  EXPECT_EQ(dataset.calibration.left.width_px, 0);
  // A bad row is still one line naming the file and the line.
  write_text(root_ / "mav0" / "cam1" / "data.csv", "#timestamp [ns],filename\n100,100.png\n12x34,200.png\n");
  const std::string error = open_error(lists_only);
  EXPECT_NE(error.find("cam1/data.csv line 3: expected '<timestamp ns>,<file name>', got '12x34,200.png'"),
            std::string::npos)
      << error;
}

TEST(GroundTruth, PosesAtStampsTakeTheNearestRowWithinTheGap) {
  eval::Trajectory truth;
  for (int k = 0; k < 3; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation().x() = k;
    truth.push_back(T, k, 1.0 + 0.01 * k);  // rows at 1.00 s, 1.01 s, 1.02 s
  }
  const std::vector<std::int64_t> stamps_ns{1'000'000'000, 1'004'000'000, 1'006'000'000,
                                            1'016'000'000, 1'040'000'000, 900'000'000};
  const std::vector<std::optional<Pose3>> poses = poses_at_stamps(truth, stamps_ns, 0.005);
  ASSERT_EQ(poses.size(), stamps_ns.size());
  ASSERT_TRUE(poses[0] && poses[1] && poses[2] && poses[3]);
  EXPECT_EQ(poses[0]->translation().x(), 0.0);  // the row's own stamp
  EXPECT_EQ(poses[1]->translation().x(), 0.0);  // 4 ms after row 0
  EXPECT_EQ(poses[2]->translation().x(), 1.0);  // 4 ms before row 1
  EXPECT_EQ(poses[3]->translation().x(), 2.0);  // 4 ms before row 2
  EXPECT_FALSE(poses[4]);                       // 20 ms after the last row
  EXPECT_FALSE(poses[5]);                       // before the first
  EXPECT_EQ(euroc_ground_truth_file("/d/mav0"), fs::path("/d/mav0/state_groundtruth_estimate0/data.csv"));
}

TEST_F(DatasetReader, EmptyFolderIsNotADataset) {
  EXPECT_NE(open_error().find(": no EuRoC (mav0/cam0/data.csv) or KITTI (times.txt + image_0/) layout found"),
            std::string::npos)
      << open_error();
  DatasetOptions kitti;
  kitti.format = DatasetFormat::kKitti;
  EXPECT_NE(open_error(kitti).find("not a KITTI sequence"), std::string::npos);
  EXPECT_THROW(parse_dataset_format("rosbag"), std::runtime_error);
}

TEST_F(DatasetReader, KittiReadsTimesImagesAndCalibration) {
  make_kitti("0.000000e+00\n1.037359e-01\n2.073381e-01\n");
  const StereoDataset dataset = open_dataset(root_);
  EXPECT_EQ(dataset.format, DatasetFormat::kKitti);
  ASSERT_EQ(dataset.frames.size(), 3u);
  EXPECT_EQ(dataset.frames[1].stamp_ns, 103'735'900);
  EXPECT_EQ(dataset.frames[2].left, root_ / "image_0" / "000002.png");
  EXPECT_EQ(dataset.frames[2].right, root_ / "image_1" / "000002.png");
  EXPECT_TRUE(dataset.calibration.input_rectified);
  EXPECT_EQ(dataset.calibration.left.width_px, kWidth);
  EXPECT_EQ(dataset.calibration.left.height_px, kHeight);
  EXPECT_NEAR(dataset.calibration.T_rl().translation().norm(), 27.0 / 50.0, 1e-9);
}

TEST_F(DatasetReader, KittiBadAndNonIncreasingTimes) {
  make_kitti("0.0\n0.1 0.2\n");
  EXPECT_NE(open_error().find("times.txt line 2: expected one time in seconds, got '0.1 0.2'"), std::string::npos)
      << open_error();
  make_kitti("0.0\n0.2\n0.1\n");
  EXPECT_NE(open_error().find("times.txt line 3: time 0.1 s is not after the previous time"), std::string::npos)
      << open_error();
  make_kitti("");
  EXPECT_NE(open_error().find("times.txt: no frames listed"), std::string::npos) << open_error();
}

TEST_F(DatasetReader, LoadsImagesBitIdentical) {
  make_euroc(kThreeRows, kThreeRows);
  const StereoDataset dataset = open_dataset(root_);
  const StereoImages images = load_stereo_images(dataset.frames[2]);
  EXPECT_EQ(images.encoding, "mono8");
  EXPECT_EQ(cv::norm(images.left, test_image(2, 0), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(images.right, test_image(2, 1), cv::NORM_INF), 0.0);
}

TEST_F(DatasetReader, MissingCorruptAndMismatchedImagesNameTheFile) {
  make_euroc(kThreeRows, kThreeRows);
  StereoDataset dataset = open_dataset(root_);
  fs::remove(dataset.frames[0].right);
  EXPECT_EQ(error_of(dataset.frames[0]), dataset.frames[0].right.string() + ": image file missing");
  write_text(dataset.frames[1].left, "not a png");
  EXPECT_EQ(error_of(dataset.frames[1]),
            dataset.frames[1].left.string() + ": cannot be decoded as an image (corrupt file?)");
  cv::imwrite(dataset.frames[2].right.string(), cv::Mat(10, 10, CV_8UC1, cv::Scalar(7)));
  EXPECT_EQ(error_of(dataset.frames[2]), "stereo pair differs in size or channels: " + dataset.frames[2].left.string() +
                                             " is 40x30x1, " + dataset.frames[2].right.string() + " is 10x10x1");
}

// With the calibration's size known, the file at fault is named: here the LEFT image is wrong
// (it used to be reported as a problem of the right file).
TEST_F(DatasetReader, WrongSizedLeftImageIsBlamedNotTheRight) {
  make_euroc(kThreeRows, kThreeRows);
  const StereoDataset dataset = open_dataset(root_);
  const cv::Size calibrated(dataset.calibration.left.width_px, dataset.calibration.left.height_px);
  ASSERT_EQ(calibrated, cv::Size(kWidth, kHeight));
  cv::imwrite(dataset.frames[0].left.string(), cv::Mat(24, 32, CV_8UC1, cv::Scalar(7)));
  try {
    load_stereo_images(dataset.frames[0], calibrated);
    ADD_FAILURE() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()), dataset.frames[0].left.string() + ": 32x24 image; the calibration says 40x30");
  }
  EXPECT_NO_THROW(load_stereo_images(dataset.frames[1], calibrated));
}

// CRC-32 as PNG computes it, to write a well-formed chunk with a corrupt size in the test.
std::uint32_t png_crc(const std::uint8_t* data, std::size_t size) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) {
    c ^= data[i];
    for (int k = 0; k < 8; ++k) c = (c & 1) != 0 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

void put_big_endian(std::vector<std::uint8_t>& bytes, std::size_t at, std::uint32_t value) {
  for (int i = 0; i < 4; ++i)
    bytes[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(value >> (24 - 8 * i));
}

// Runs `load` with stderr captured; returns what was printed there.
template <typename F>
std::string captured_stderr(F&& load) {
  std::fflush(stderr);
  const fs::path capture = fs::temp_directory_path() / ("heslam_stderr_" + std::to_string(::getpid()));
  const int saved = ::dup(STDERR_FILENO);
  FILE* file = std::fopen(capture.c_str(), "w");
  ::dup2(::fileno(file), STDERR_FILENO);
  load();
  std::fflush(stderr);
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  std::fclose(file);
  std::ifstream in(capture);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(capture);
  return text;
}

// A truncated PNG, one with a flipped byte, and one whose header claims 100000x400000 pixels: one
// line naming the file and what is wrong, nothing from libpng on stderr, no OpenCV allocation error.
TEST_F(DatasetReader, DamagedPngFilesAreNamedWithoutLibpngNoise) {
  make_euroc(kThreeRows, kThreeRows);
  const StereoDataset dataset = open_dataset(root_);
  std::vector<std::uint8_t> png;
  cv::imencode(".png", test_image(0, 0), png);
  auto write_bytes = [](const fs::path& path, const std::vector<std::uint8_t>& bytes) {
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  };

  std::vector<std::uint8_t> truncated(png.begin(), png.begin() + static_cast<std::ptrdiff_t>(png.size() / 2));
  write_bytes(dataset.frames[0].left, truncated);
  std::string error;
  EXPECT_EQ(captured_stderr([&] { error = error_of(dataset.frames[0]); }), "");
  EXPECT_EQ(error.rfind(dataset.frames[0].left.string() + ": truncated PNG: chunk IDAT at byte ", 0), 0u) << error;

  std::vector<std::uint8_t> flipped = png;
  flipped[png.size() - 20] ^= 0x40;  // inside the image data
  write_bytes(dataset.frames[1].right, flipped);
  EXPECT_EQ(captured_stderr([&] { error = error_of(dataset.frames[1]); }), "");
  EXPECT_EQ(error.rfind(dataset.frames[1].right.string() + ": corrupt PNG: chunk ", 0), 0u) << error;
  EXPECT_NE(error.find("fails its CRC check"), std::string::npos) << error;

  std::vector<std::uint8_t> huge = png;
  put_big_endian(huge, 16, 100000);  // IHDR width, then height, after signature, length and type
  put_big_endian(huge, 20, 400000);
  put_big_endian(huge, 29, png_crc(huge.data() + 12, 17));  // IHDR type + 13 data bytes
  write_bytes(dataset.frames[2].left, huge);
  EXPECT_EQ(error_of(dataset.frames[2]), dataset.frames[2].left.string() +
                                             ": PNG header says 100000x400000 pixels: expected 1..8192 px per side "
                                             "(corrupt file?)");
}

TEST_F(DatasetReader, TimeWindowSelectsFramesBySecondsFromStart) {
  make_kitti("0.0\n0.5\n1.0\n");
  StereoDataset dataset = open_dataset(root_);
  select_time_window(dataset, 0.4, 0.5);
  ASSERT_EQ(dataset.frames.size(), 1u);
  EXPECT_EQ(dataset.frames[0].stamp_ns, 500'000'000);
  StereoDataset all = open_dataset(root_);
  select_time_window(all, 0.5, 0.0);
  EXPECT_EQ(all.frames.size(), 2u);
  try {
    select_time_window(all, 10.0, 0.0);
    ADD_FAILURE() << "an empty window must be an error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "--start-offset/--duration: no frame in [10 s, end) of a 0.5 s recording");
  }
}

TEST(DatasetOnRealData, EurocV101HeadHas95PairsAndSkipsTheUnpairedTail) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const StereoDataset dataset = open_dataset(test::shared_dataset("euroc_v101_head"));
  EXPECT_EQ(dataset.frames.size(), 95u);
  EXPECT_EQ(dataset.skipped_rows, 4);  // cam1/data.csv lists 4 rows past the end of cam0
  EXPECT_EQ(dataset.frames.front().stamp_ns, 1403715273262142976);
  EXPECT_NEAR(dataset.duration_s(), 4.7, 1e-3);
  const StereoImages images = load_stereo_images(dataset.frames.front());
  EXPECT_EQ(images.left.cols, 752);
  EXPECT_EQ(images.left.rows, 480);
  EXPECT_EQ(images.encoding, "mono8");
}

}  // namespace
}  // namespace heslam
