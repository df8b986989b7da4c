// heslam-camera's DDS-free parts with known answers: pairing by stamp, the one-frame slot's dropped
// count, Kalibr camchains (the same rectification as the EuRoC sensor.yaml they were written from),
// and the capture's checks on small generated folders and videos (odd side-by-side width, wrong
// resolution, colour converted once, stamps going backwards, unpaired rows, unreadable images).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "components/core/camera/stereo_rectifier.hpp"
#include "test_support.hpp"
#include "tools/camera/camera_calibration.hpp"
#include "tools/camera/camera_options.hpp"
#include "tools/camera/latest_slot.hpp"
#include "tools/camera/stereo_capture.hpp"
#include "tools/camera/stereo_pairing.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
constexpr std::int64_t kMs = 1'000'000;
const cv::Size kSize(64, 32);  // each camera's image in the generated inputs

std::vector<std::int64_t> pair_all(std::vector<std::int64_t> left, std::vector<std::int64_t> right,
                                   std::int64_t tolerance_ns, PairingCounts& counts,
                                   std::vector<std::int64_t>* right_of_pairs = nullptr) {
  std::size_t l = 0, r = 0;
  const std::function<std::optional<std::int64_t>()> next_left = [&]() -> std::optional<std::int64_t> {
    return l < left.size() ? std::optional(left[l++]) : std::nullopt;
  };
  const std::function<std::optional<std::int64_t>()> next_right = [&]() -> std::optional<std::int64_t> {
    return r < right.size() ? std::optional(right[r++]) : std::nullopt;
  };
  const std::function<std::int64_t(const std::int64_t&)> stamp = [](const std::int64_t& s) { return s; };
  std::vector<std::int64_t> lefts;
  while (auto pair = next_stereo_pair<std::int64_t>(next_left, next_right, stamp, tolerance_ns, counts)) {
    lefts.push_back(pair->first);
    if (right_of_pairs) right_of_pairs->push_back(pair->second);
  }
  return lefts;
}

TEST(StereoPairing, PairsWithinToleranceAndCountsTheRest) {
  PairingCounts counts;
  std::vector<std::int64_t> rights;
  // Right misses 50 ms, left misses 200 ms; right runs 3 ms late (within 5 ms).
  const auto lefts = pair_all({0, 50 * kMs, 100 * kMs, 150 * kMs, 250 * kMs},
                              {3 * kMs, 103 * kMs, 153 * kMs, 203 * kMs, 253 * kMs}, 5 * kMs, counts, &rights);
  EXPECT_EQ(lefts, (std::vector<std::int64_t>{0, 100 * kMs, 150 * kMs, 250 * kMs}));
  EXPECT_EQ(rights, (std::vector<std::int64_t>{3 * kMs, 103 * kMs, 153 * kMs, 253 * kMs}));
  EXPECT_EQ(counts.unpaired_left, 1u);
  EXPECT_EQ(counts.unpaired_right, 1u);
}

TEST(StereoPairing, OutsideToleranceNothingPairsAndTheEndCountsTheLastRead) {
  PairingCounts counts;
  const auto lefts = pair_all({0, 50 * kMs}, {20 * kMs, 70 * kMs}, 5 * kMs, counts);
  EXPECT_TRUE(lefts.empty());
  // 0 < 20: left 0 unpaired; 50 > 20: right 20 unpaired; 50 < 70: left 50 unpaired; left ends with 70 read.
  EXPECT_EQ(counts.unpaired_left, 2u);
  EXPECT_EQ(counts.unpaired_right, 2u);
}

TEST(LatestSlot, ReplacingAnUntakenFrameCountsItDropped) {
  LatestSlot<int> slot;
  EXPECT_FALSE(slot.put(1));
  EXPECT_TRUE(slot.put(2));  // 1 was never taken
  EXPECT_EQ(slot.take(std::chrono::milliseconds(0)), 2);
  EXPECT_FALSE(slot.put(3));
  EXPECT_EQ(slot.take(std::chrono::milliseconds(0)), 3);
  EXPECT_EQ(slot.dropped(), 1u);
  EXPECT_FALSE(slot.finished());
  slot.close();
  EXPECT_TRUE(slot.finished());
  EXPECT_EQ(slot.take(std::chrono::milliseconds(1000)), std::nullopt);  // at once: closed
}

std::string matrix_rows(const Pose3& pose, const std::string& indent) {
  std::string text;
  for (int r = 0; r < 4; ++r) {
    char row[200];
    std::snprintf(row, sizeof(row), "%s- [%.17g, %.17g, %.17g, %.17g]\n", indent.c_str(), pose.matrix()(r, 0),
                  pose.matrix()(r, 1), pose.matrix()(r, 2), pose.matrix()(r, 3));
    text += row;
  }
  return text;
}

std::string kalibr_camera(const CameraModel& camera) {
  char text[600];
  std::snprintf(text, sizeof(text),
                "  camera_model: pinhole\n  distortion_coeffs: [%.17g, %.17g, %.17g, %.17g]\n"
                "  distortion_model: radtan\n  intrinsics: [%.17g, %.17g, %.17g, %.17g]\n  resolution: [%d, %d]\n",
                camera.distortion[0], camera.distortion[1], camera.distortion[2], camera.distortion[3], camera.fx_px,
                camera.fy_px, camera.cx_px, camera.cy_px, camera.width_px, camera.height_px);
  return text;
}

// A camchain as kalibr_calibrate_cameras writes it (PyYAML: no header, list items at the key's indent).
std::string kalibr_camchain(const StereoCalibration& euroc) {
  return "cam0:\n  T_cam_imu:\n" + matrix_rows(euroc.left.T_BS.inverse(), "  ") + "  cam_overlaps: [1]\n" +
         kalibr_camera(euroc.left) + "  rostopic: /cam0/image_raw\ncam1:\n  T_cam_imu:\n" +
         matrix_rows(euroc.right.T_BS.inverse(), "  ") + "  T_cn_cnm1:\n" + matrix_rows(euroc.T_rl(), "  ") +
         "  cam_overlaps: [0]\n" + kalibr_camera(euroc.right) + "  rostopic: /cam1/image_raw\n";
}

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
}

TEST(KalibrCamchain, SameRectificationAsTheEurocSensorYamlItWasWrittenFrom) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path mav0 = test::shared_dataset("euroc_mh01_handheld") / "mav0";
  const test::ScratchDir dir("camera_kalibr");
  const StereoCalibration euroc = load_camera_calibration(mav0);
  write_text(dir.path() / "camchain.yaml", kalibr_camchain(euroc));
  ASSERT_EQ(detect_calibration_format(dir.path() / "camchain.yaml"), CalibrationFormat::kKalibr);
  const StereoCalibration kalibr = load_camera_calibration(dir.path() / "camchain.yaml");

  const StereoRectifier from_euroc(euroc);
  const StereoRectifier from_kalibr(kalibr);
  const PinholeStereo& a = from_euroc.camera();
  const PinholeStereo& b = from_kalibr.camera();
  EXPECT_EQ(a.width_px, b.width_px);
  EXPECT_EQ(a.height_px, b.height_px);
  EXPECT_NEAR(a.fx_px, b.fx_px, 1e-9);
  EXPECT_NEAR(a.fy_px, b.fy_px, 1e-9);
  EXPECT_NEAR(a.cx_px, b.cx_px, 1e-9);
  EXPECT_NEAR(a.cy_px, b.cy_px, 1e-9);
  EXPECT_NEAR(a.baseline_m, b.baseline_m, 1e-12);
  EXPECT_LT((from_euroc.T_B_rect().matrix() - from_kalibr.T_B_rect().matrix()).cwiseAbs().maxCoeff(), 1e-12);

  // The same raw pair gives the same rectified pixels.
  const cv::Mat left = cv::imread((mav0 / "cam0/data/1403636584763555584.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat right = cv::imread((mav0 / "cam1/data/1403636584763555584.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(left.empty());
  cv::Mat left_a, right_a, left_b, right_b;
  from_euroc.rectify(left, right, left_a, right_a);
  from_kalibr.rectify(left, right, left_b, right_b);
  EXPECT_EQ(cv::norm(left_a, left_b, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(right_a, right_b, cv::NORM_INF), 0.0);
}

TEST(KalibrCamchain, RefusesUnknownModelsAndMissingExtrinsicByName) {
  const test::ScratchDir dir("camera_kalibr_bad");
  const std::string cam = "  camera_model: pinhole\n  intrinsics: [400, 400, 320, 240]\n  resolution: [640, 480]\n";
  const auto error_of = [&](const std::string& text) {
    write_text(dir.path() / "c.yaml", text);
    try {
      load_camera_calibration(dir.path() / "c.yaml");
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("cam0:\n" + cam + "  distortion_model: fov\n  distortion_coeffs: [0.9]\n" + "cam1:\n" + cam +
                     "  T_cn_cnm1:\n  - [1, 0, 0, -0.1]\n  - [0, 1, 0, 0]\n  - [0, 0, 1, 0]\n" + "  - [0, 0, 0, 1]\n")
                .find("c.yaml: cam0.distortion_model: 'fov' is not supported"),
            std::string::npos);
  EXPECT_NE(error_of("cam0:\n" + cam + "cam1:\n" + cam).find("c.yaml: cam1.T_cn_cnm1: missing"), std::string::npos);
  EXPECT_NE(error_of("cam0:\n  camera_model: omni\n").find("cam0.camera_model: 'omni' is not supported"),
            std::string::npos);
  EXPECT_NE(error_of("cam0:\n" + cam + "cam1:\n" + cam + "  T_cn_cnm1:\n  - [2, 0, 0, 0]\n  - [0, 1, 0, 0]\n" +
                     "  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n")
                .find("cam1.T_cn_cnm1: not a rigid transform"),
            std::string::npos);
  // No distortion: a pinhole camera without distortion_model.
  EXPECT_EQ(error_of("cam0:\n" + cam + "cam1:\n" + cam + "  T_cn_cnm1:\n  - [1, 0, 0, -0.1]\n  - [0, 1, 0, 0]\n" +
                     "  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n"),
            "no error");
}

TEST(CameraCalibration, OrbSlamSettingsFilesGoThroughTheSettingsReader) {
  for (const char* name : {"EuRoC.yaml", "EuRoC_ORB-SLAM3.yaml"}) {
    SCOPED_TRACE(name);
    const fs::path file = test::source_dir() / "config/camera" / name;
    EXPECT_EQ(detect_calibration_format(file), CalibrationFormat::kOrbSlam);
    const StereoCalibration calibration = load_camera_calibration(file);
    EXPECT_EQ(calibration.left.width_px, 752);
    EXPECT_EQ(calibration.left.height_px, 480);
    EXPECT_NO_THROW(StereoRectifier{calibration});
  }
  EXPECT_NE(std::string(to_string(CalibrationFormat::kOrbSlam)).find("ORB-SLAM"), std::string::npos);
}

TEST(KalibrCamchain, YamlFixedForOpenCv) {
  EXPECT_EQ(kalibr_yaml_for_opencv("cam1:\n  T_cn_cnm1:\n  - [1, 0]\n  - [0, 1]\n  x: [1]\n"),
            "%YAML:1.0\n---\ncam1:\n  T_cn_cnm1:\n    - [1, 0]\n    - [0, 1]\n  x: [1]\n");
}

// A test image whose pixels say which frame and camera it is.
cv::Mat pattern(int frame, int camera, cv::Size size = kSize) {
  cv::Mat image(size, CV_8UC1);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(frame * 7 + camera * 100 + x + y);
  return image;
}

cv::Mat side_by_side(int frame) {
  cv::Mat both;
  cv::hconcat(pattern(frame, 0), pattern(frame, 1), both);
  return both;
}

struct Collected {
  std::vector<CapturedFrame> frames;
  std::vector<std::string> warnings;
  CaptureCounts counts;
  std::string error;
  std::string end_reason;
};

Collected capture_all(const std::string& source, CameraLayout layout, cv::Size calibrated = kSize,
                      std::int64_t first_stamp_ns = 1'000'000'000) {
  Collected out;
  const Warn warn = [&out](const std::string&, const std::string& line) { out.warnings.push_back(line); };
  StreamOptions stream_options;
  stream_options.fps = 20.0;
  CaptureOptions options;
  options.calibrated_size = calibrated;
  options.calibration_source = "CALIB";
  options.first_stamp_ns = first_stamp_ns;
  options.pair_tolerance_ns = 5 * kMs;
  try {
    StereoCapture capture(open_source(source, layout, stream_options, warn), options, warn);
    try {
      while (auto frame = capture.next()) out.frames.push_back(std::move(*frame));
    } catch (const std::exception& error) {
      out.error = error.what();
    }
    out.counts = capture.counts();
    out.end_reason = capture.end_reason();
  } catch (const std::exception& error) {
    out.error = error.what();
  }
  return out;
}

// An EuRoC-style camera folder: data.csv rows in the given order, images in data/.
void write_camera_folder(const fs::path& folder, const std::vector<std::pair<std::int64_t, int>>& rows, int camera) {
  fs::create_directories(folder / "data");
  std::ofstream csv(folder / "data.csv");
  csv << "#timestamp [ns],filename\n";
  for (const auto& [stamp, frame] : rows) {
    const std::string name = std::to_string(stamp) + ".png";
    cv::imwrite((folder / "data" / name).string(), pattern(frame, camera));
    csv << stamp << "," << name << "\n";
  }
}

TEST(StereoCapture, EurocFoldersPairByStampCountUnpairedAndBackwardsStamps) {
  const test::ScratchDir dir("camera_folders");
  const fs::path mav0 = dir.path() / "mav0";
  // cam1 lacks frame 1; cam0's frame 3 is stamped before frame 2 (out of order in data.csv).
  write_camera_folder(mav0 / "cam0", {{100 * kMs, 0}, {150 * kMs, 1}, {200 * kMs, 2}, {180 * kMs, 3}, {300 * kMs, 4}},
                      0);
  write_camera_folder(mav0 / "cam1", {{100 * kMs, 0}, {200 * kMs, 2}, {180 * kMs, 3}, {300 * kMs, 4}}, 1);
  const Collected out = capture_all(dir.path().string(), CameraLayout::kAuto);
  ASSERT_EQ(out.error, "");
  ASSERT_EQ(out.frames.size(), 3u);
  EXPECT_EQ(out.frames[0].stamp_ns, 100 * kMs);
  EXPECT_EQ(out.frames[1].stamp_ns, 200 * kMs);
  EXPECT_EQ(out.frames[2].stamp_ns, 300 * kMs);
  EXPECT_EQ(cv::norm(out.frames[1].images.left, pattern(2, 0), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(out.frames[1].images.right, pattern(2, 1), cv::NORM_INF), 0.0);
  EXPECT_EQ(out.counts.pairing.unpaired_left, 1u);
  EXPECT_EQ(out.counts.pairing.unpaired_right, 0u);
  EXPECT_EQ(out.counts.stamps_backwards, 1u);
  ASSERT_EQ(out.warnings.size(), 1u);
  EXPECT_EQ(out.warnings[0], "stamps going backwards: frame stamped 180000000 ns after 200000000 ns; skipped");
  EXPECT_EQ(out.end_reason, "end of " + (mav0 / "cam0").string() + " after 5 images");  // the stream that ended
}

TEST(StereoCapture, PlainSideBySideFolderStampsFromTheFirstStampAndFps) {
  const test::ScratchDir dir("camera_plain");
  for (int i = 0; i < 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame%03d.png", i);
    cv::imwrite((dir.path() / name).string(), side_by_side(i));
  }
  write_text(dir.path() / "notes.txt", "not an image");
  fs::copy_file(dir.path() / "frame000.png", dir.path() / "frame001a.png");
  write_text(dir.path() / "frame001a.png", "truncated");  // unreadable: skipped and counted
  const Collected out = capture_all(dir.path().string(), CameraLayout::kSideBySide);
  ASSERT_EQ(out.error, "");
  ASSERT_EQ(out.frames.size(), 3u);
  EXPECT_EQ(out.counts.unreadable, 1u);
  // Stamps: the first stamp + index / fps (frame001a held index 2).
  EXPECT_EQ(out.frames[0].stamp_ns, 1'000'000'000);
  EXPECT_EQ(out.frames[1].stamp_ns, 1'050'000'000);
  EXPECT_EQ(out.frames[2].stamp_ns, 1'150'000'000);
  EXPECT_EQ(cv::norm(out.frames[2].images.left, pattern(2, 0), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(out.frames[2].images.right, pattern(2, 1), cv::NORM_INF), 0.0);
}

// A lossless side-by-side video (FFV1 in AVI, which Debian's OpenCV writes through FFmpeg).
fs::path write_video(const fs::path& file, int frames, cv::Size size, bool colour = false) {
  cv::VideoWriter writer(file.string(), cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 20.0, size, colour);
  if (!writer.isOpened()) return {};
  for (int i = 0; i < frames; ++i) {
    cv::Mat image =
        size == cv::Size(kSize.width * 2, kSize.height) ? side_by_side(i) : cv::Mat(size, CV_8UC1, cv::Scalar(i));
    if (colour) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);
    writer.write(image);
  }
  return file;
}

TEST(StereoCapture, SideBySideVideoIsLosslessGreyOnceConvertedAndStampedByPresentationTime) {
  const test::ScratchDir dir("camera_video");
  const fs::path video = write_video(dir.path() / "sbs.avi", 4, cv::Size(kSize.width * 2, kSize.height));
  if (video.empty()) GTEST_SKIP() << "this OpenCV cannot write FFV1 video";
  const Collected out = capture_all(video.string(), CameraLayout::kAuto);
  ASSERT_EQ(out.error, "");
  ASSERT_EQ(out.frames.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(out.frames[i].stamp_ns, 1'000'000'000 + i * 50 * kMs);
    EXPECT_EQ(out.frames[i].stamp_ns, out.frames[i].right_stamp_ns);
    EXPECT_EQ(out.frames[i].images.encoding, "mono8");
    EXPECT_EQ(cv::norm(out.frames[i].images.left, pattern(i, 0), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(out.frames[i].images.right, pattern(i, 1), cv::NORM_INF), 0.0);
  }
  // FFmpeg decodes grey FFV1 to BGR: converted back, said once.
  ASSERT_EQ(out.warnings.size(), 1u);
  EXPECT_NE(out.warnings[0].find("sbs.avi delivers 3-channel images: converted to mono8 (grey)"), std::string::npos);
}

TEST(StereoCapture, OddSideBySideWidthAndWrongResolutionStopWithOneLine) {
  const test::ScratchDir dir("camera_bad_video");
  // FFV1 cannot hold an odd width: a folder of such images.
  const fs::path odd = dir.path() / "odd";
  fs::create_directories(odd);
  cv::imwrite((odd / "0.png").string(), cv::Mat(kSize.height, kSize.width * 2 + 1, CV_8UC1, cv::Scalar(9)));
  EXPECT_EQ(capture_all(odd.string(), CameraLayout::kSideBySide).error,
            odd.string() + ": side-by-side frame is 129 px wide (odd): it cannot be two images of one size");
  const fs::path small = write_video(dir.path() / "small.avi", 2, cv::Size(kSize.width * 2, kSize.height));
  if (small.empty()) GTEST_SKIP() << "this OpenCV cannot write FFV1 video";
  EXPECT_EQ(capture_all(small.string(), CameraLayout::kSideBySide, cv::Size(752, 480)).error,
            "wrong resolution: " + small.string() +
                " delivers 64x32 images per camera (each half), the calibration CALIB is for 752x480");
}

TEST(StereoCapture, SourcesThatCannotBeOpenedSayWhy) {
  EXPECT_EQ(capture_all("/dev/heslam-no-such-camera", CameraLayout::kSideBySide).error,
            "camera /dev/heslam-no-such-camera: cannot open the V4L2 device (no such device)");
  EXPECT_EQ(capture_all("/nonexistent/clip.avi", CameraLayout::kSideBySide).error,
            "/nonexistent/clip.avi: no such device, video file or image folder");
  EXPECT_NE(capture_all("a.avi,b.avi,c.avi", CameraLayout::kAuto).error.find("at most two sources"), std::string::npos);
  const test::ScratchDir dir("camera_plain_nofps");
  cv::imwrite((dir.path() / "a.png").string(), side_by_side(0));
  EXPECT_NE(capture_all(dir.path().string(), CameraLayout::kTwoDevices).error.find("two-devices needs LEFT,RIGHT"),
            std::string::npos);
}

TEST(CameraOptions, ParsesAndRefusesWithOneLine) {
  const CameraOptions options = parse_camera_options(
      {"/dev/video0", "--calibration", "c.yaml", "--layout", "side-by-side", "--end", "fail", "--first-stamp-ns", "5"});
  EXPECT_EQ(options.source, "/dev/video0");
  EXPECT_EQ(options.layout, CameraLayout::kSideBySide);
  EXPECT_TRUE(options.end_is_failure);
  EXPECT_EQ(options.first_stamp_ns, 5);
  const auto error_of = [](const std::vector<std::string>& args) {
    try {
      parse_camera_options(args);
    } catch (const std::exception& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of({"x.avi"}), "missing --calibration DIR|FILE (see --help)");
  EXPECT_EQ(error_of({"x.avi", "--calibration", "c", "--end", "maybe"}), "--end: expected finish or fail, got 'maybe'");
  EXPECT_NE(error_of({"x.avi", "--calibration", "c", "--layout", "stacked"}).find("--layout"), std::string::npos);
}

}  // namespace
}  // namespace heslam
