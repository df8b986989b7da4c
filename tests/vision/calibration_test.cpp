// Calibration loaders and rectification: every format gives the same rectified model for the same rig
// (EuRoC's VI-Sensor), and each malformed file gives one clear line naming the file and the field.
#include <fstream>
#include <limits>
#include <string>
#include <thread>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// ORB-SLAM2's Examples/Stereo/EuRoC.yaml: the rectified model of this rig (stereoRectify, alpha 0).
constexpr double kOrbSlamFx = 435.2046959714599;
constexpr double kOrbSlamCx = 367.4517211914062;
constexpr double kOrbSlamCy = 252.2008514404297;
constexpr double kOrbSlamBf = 47.90639384423901;

constexpr const char* kEurocCam0 = R"(# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam0 (MT9M034)
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
)";

constexpr const char* kEurocCam1 = R"(sensor_type: camera
comment: VI-Sensor cam1 (MT9M034)
T_BS:
  cols: 4
  rows: 4
  data: [0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,
         0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,
        -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [457.587, 456.134, 379.999, 255.238] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28368365,  0.07451284, -0.00010473, -3.55590700e-05]
)";

fs::path scratch_dir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("heslam_calibration_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file) << text;
}

fs::path write_euroc(const std::string& name, const std::string& cam0, const std::string& cam1) {
  const fs::path mav0 = scratch_dir(name) / "mav0";
  write(mav0 / "cam0" / "sensor.yaml", cam0);
  write(mav0 / "cam1" / "sensor.yaml", cam1);
  return mav0;
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return text.replace(pos, from.size(), to);
}

// The error of loading `load()`; empty when it did not throw.
template <typename F>
std::string error_of(F load) {
  try {
    load();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}

void expect_one_line_naming(const std::string& error, const std::string& file_part, const std::string& field) {
  EXPECT_FALSE(error.empty());
  EXPECT_EQ(error.find('\n'), std::string::npos) << error;
  EXPECT_NE(error.find(file_part), std::string::npos) << error;
  EXPECT_NE(error.find(field), std::string::npos) << error;
}

void expect_same_model(const PinholeStereo& a, const PinholeStereo& b, double tolerance_px) {
  EXPECT_NEAR(a.fx_px, b.fx_px, tolerance_px);
  EXPECT_NEAR(a.fy_px, b.fy_px, tolerance_px);
  EXPECT_NEAR(a.cx_px, b.cx_px, tolerance_px);
  EXPECT_NEAR(a.cy_px, b.cy_px, tolerance_px);
  EXPECT_NEAR(a.bf(), b.bf(), tolerance_px);
  EXPECT_EQ(a.width_px, b.width_px);
  EXPECT_EQ(a.height_px, b.height_px);
}

TEST(Calibration, EurocSensorYamlAgreesWithOrbSlamSettings) {
  const StereoCalibration calibration = load_euroc_calibration(write_euroc("euroc", kEurocCam0, kEurocCam1));
  EXPECT_FALSE(calibration.input_rectified);
  EXPECT_EQ(calibration.left.width_px, 752);
  EXPECT_EQ(calibration.left.distortion.size(), 4u);
  EXPECT_DOUBLE_EQ(calibration.rate_hz, 20.0);
  // EuRoC baseline is about 11 cm along +x of cam0.
  EXPECT_NEAR(calibration.T_rl().translation().norm(), 0.110, 0.001);
  EXPECT_LT(calibration.T_rl().translation().x(), 0.0);

  const StereoRectifier rectifier(calibration);
  const PinholeStereo& camera = rectifier.camera();
  // Same baseline and the same rectifying rotation as ORB-SLAM2's published settings. The new camera
  // matrix for alpha 0 differs slightly: OpenCV 4.6 picks fx 436.2, (cx, cy) (364.4, 257.0) where the
  // OpenCV 2.4 used for ORB-SLAM2's file picked 435.2, (367.5, 252.2); both keep only valid pixels.
  EXPECT_NEAR(camera.baseline_m, kOrbSlamBf / kOrbSlamFx, 1e-5);
  EXPECT_NEAR(camera.fx_px, kOrbSlamFx, 0.005 * kOrbSlamFx);
  EXPECT_NEAR(camera.cx_px, kOrbSlamCx, 6.0);
  EXPECT_NEAR(camera.cy_px, kOrbSlamCy, 6.0);
  EXPECT_EQ(camera.fx_px, camera.fy_px);

  const StereoCalibration orbslam = load_orbslam_settings(test::source_dir() / "config" / "camera" / "EuRoC.yaml");
  ASSERT_TRUE(orbslam.explicit_rectification.has_value());
  const StereoRectifier from_orbslam(orbslam);
  EXPECT_NEAR(from_orbslam.camera().fx_px, kOrbSlamFx, 1e-9);
  EXPECT_NEAR(from_orbslam.camera().bf(), kOrbSlamBf, 1e-9);
  // Rectified-left -> cam0 rotation (R1^T): from EuRoC via stereoRectify, from ORB-SLAM2 as LEFT.R^T.
  const Eigen::Matrix3d R1t_euroc = (calibration.left.T_BS.inverse() * rectifier.T_B_rect()).linear();
  const Eigen::Matrix3d R1t_orbslam = from_orbslam.T_B_rect().linear();
  EXPECT_LT(Eigen::AngleAxisd(R1t_euroc.transpose() * R1t_orbslam).angle(), 1e-4);
  // The rig's extrinsics recovered from R/P agree with the EuRoC T_BS pair.
  EXPECT_LT((orbslam.T_rl().translation() - calibration.T_rl().translation()).norm(), 1e-4);
  EXPECT_LT(Eigen::AngleAxisd(orbslam.T_rl().linear().transpose() * calibration.T_rl().linear()).angle(), 1e-4);
}

std::string matrix_yaml(const std::string& key, const Eigen::MatrixXd& m) {
  std::string text = key + ": !!opencv-matrix\n   rows: " + std::to_string(m.rows()) +
                     "\n   cols: " + std::to_string(m.cols()) + "\n   dt: d\n   data: [";
  char number[64];
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < m.cols(); ++c) {
      std::snprintf(number, sizeof number, "%s%.17g", (r + c) ? ", " : "", m(r, c));
      text += number;
    }
  }
  return text + "]\n";
}

TEST(Calibration, SameRigGivesSameModelInEveryFormat) {
  const StereoCalibration euroc = load_euroc_calibration(write_euroc("same", kEurocCam0, kEurocCam1));
  const StereoRectifier from_euroc(euroc);
  const PinholeStereo& m = from_euroc.camera();
  const fs::path dir = scratch_dir("formats");

  // ORB-SLAM2 raw-image settings holding this rig's K, D and its rectification R, P.
  const Eigen::Matrix3d R1 = (euroc.left.T_BS.inverse() * from_euroc.T_B_rect()).linear().transpose();
  const Eigen::Matrix3d R2 = R1 * euroc.T_rl().linear().transpose();
  Eigen::Matrix<double, 3, 4> P1;
  P1 << m.fx_px, 0, m.cx_px, 0, 0, m.fy_px, m.cy_px, 0, 0, 0, 1, 0;
  Eigen::Matrix<double, 3, 4> P2 = P1;
  P2(0, 3) = -m.bf();
  auto K = [](const CameraModel& c) {
    Eigen::Matrix3d k;
    k << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1;
    return k;
  };
  auto D = [](const CameraModel& c) {
    return Eigen::RowVectorXd(Eigen::Map<const Eigen::RowVectorXd>(c.distortion.data(), 4));
  };
  char header[512];
  std::snprintf(header, sizeof header,
                "%%YAML:1.0\nCamera.fx: %.17g\nCamera.fy: %.17g\nCamera.cx: %.17g\nCamera.cy: %.17g\n"
                "Camera.width: %d\nCamera.height: %d\nCamera.fps: 20.0\nCamera.bf: %.17g\n",
                m.fx_px, m.fy_px, m.cx_px, m.cy_px, m.width_px, m.height_px, m.bf());
  write(dir / "raw.yaml",
        std::string(header) + matrix_yaml("LEFT.K", K(euroc.left)) + matrix_yaml("LEFT.D", D(euroc.left)) +
            matrix_yaml("LEFT.R", R1) + matrix_yaml("LEFT.P", P1) + matrix_yaml("RIGHT.K", K(euroc.right)) +
            matrix_yaml("RIGHT.D", D(euroc.right)) + matrix_yaml("RIGHT.R", R2) + matrix_yaml("RIGHT.P", P2));
  const StereoCalibration raw_settings = load_orbslam_settings(dir / "raw.yaml");
  expect_same_model(StereoRectifier(raw_settings).camera(), m, 1e-9);
  EXPECT_LT((raw_settings.T_rl().translation() - euroc.T_rl().translation()).norm(), 1e-9);

  // The rectified model written as KITTI calib.txt and as ORB-SLAM2 rectified (KITTI-style) settings.
  char line[512];
  std::snprintf(line, sizeof line,
                "P0: %.17g 0 %.17g 0 0 %.17g %.17g 0 0 0 1 0\nP1: %.17g 0 %.17g %.17g 0 %.17g %.17g 0 0 0 1 0\n",
                m.fx_px, m.cx_px, m.fy_px, m.cy_px, m.fx_px, m.cx_px, -m.bf(), m.fy_px, m.cy_px);
  write(dir / "calib.txt", std::string("P2: 1 0 0 0 0 1 0 0 0 0 1 0\n") + line);
  const StereoRectifier from_kitti(load_kitti_calibration(dir / "calib.txt", m.width_px, m.height_px));
  expect_same_model(from_kitti.camera(), m, 1e-9);

  write(dir / "rectified.yaml", std::string(header) + "Camera.k1: 0.0\n");
  const StereoCalibration rectified = load_orbslam_settings(dir / "rectified.yaml");
  EXPECT_TRUE(rectified.input_rectified);
  expect_same_model(StereoRectifier(rectified).camera(), m, 1e-9);
}

// ORB-SLAM3's settings format (File.version "1.0") for the same rig: a raw pair (Camera1/Camera2 with
// Stereo.T_c1_c2, IMU.T_b_c1 placing it on the body) and a rectified one (Stereo.b) give the same model
// as the EuRoC files; what heslam cannot honour is refused in one line naming the key.
TEST(Calibration, OrbSlam3SettingsGiveTheSameModelOrOneClearLine) {
  const StereoCalibration euroc = load_euroc_calibration(write_euroc("orbslam3", kEurocCam0, kEurocCam1));
  const PinholeStereo m = StereoRectifier(euroc).camera();
  const fs::path dir = scratch_dir("orbslam3");
  auto camera = [](const std::string& name, const CameraModel& c) {
    char text[512];
    std::snprintf(text, sizeof text,
                  "%s.fx: %.17g\n%s.fy: %.17g\n%s.cx: %.17g\n%s.cy: %.17g\n%s.k1: %.17g\n%s.k2: %.17g\n"
                  "%s.p1: %.17g\n%s.p2: %.17g\n",
                  name.c_str(), c.fx_px, name.c_str(), c.fy_px, name.c_str(), c.cx_px, name.c_str(), c.cy_px,
                  name.c_str(), c.distortion[0], name.c_str(), c.distortion[1], name.c_str(), c.distortion[2],
                  name.c_str(), c.distortion[3]);
    return std::string(text);
  };
  const std::string header =
      "%YAML:1.0\nFile.version: \"1.0\"\nCamera.type: \"PinHole\"\n"
      "Camera.width: 752\nCamera.height: 480\nCamera.fps: 20\nStereo.ThDepth: 60.0\n";
  const Eigen::Matrix4d T_c1_c2 = (euroc.left.T_BS.inverse() * euroc.right.T_BS).matrix();
  const std::string raw = header + camera("Camera1", euroc.left) + camera("Camera2", euroc.right) +
                          matrix_yaml("Stereo.T_c1_c2", T_c1_c2) + matrix_yaml("IMU.T_b_c1", euroc.left.T_BS.matrix());
  write(dir / "raw.yaml", raw);
  const StereoCalibration from_raw = load_orbslam_settings(dir / "raw.yaml");
  EXPECT_FALSE(from_raw.input_rectified);
  EXPECT_DOUBLE_EQ(from_raw.rate_hz, 20.0);
  expect_same_model(StereoRectifier(from_raw).camera(), m, 1e-6);
  EXPECT_LT((from_raw.left.T_BS.matrix() - euroc.left.T_BS.matrix()).norm(), 1e-9);
  EXPECT_LT((from_raw.right.T_BS.matrix() - euroc.right.T_BS.matrix()).norm(), 1e-9);

  char rectified_camera[256];
  std::snprintf(rectified_camera, sizeof rectified_camera,
                "Camera1.fx: %.17g\nCamera1.fy: %.17g\nCamera1.cx: %.17g\nCamera1.cy: %.17g\nStereo.b: %.17g\n",
                m.fx_px, m.fy_px, m.cx_px, m.cy_px, m.baseline_m);
  write(dir / "rectified.yaml", header + rectified_camera);
  const StereoCalibration from_rectified = load_orbslam_settings(dir / "rectified.yaml");
  EXPECT_TRUE(from_rectified.input_rectified);
  expect_same_model(StereoRectifier(from_rectified).camera(), m, 1e-9);

  // A camera type heslam does not rectify (KannalaBrandt8 is read: tests/camera/fisheye_test.cpp).
  const std::string other = replace(raw, "\"PinHole\"", "\"Rectified\"");
  write(dir / "other.yaml", other);
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "other.yaml"); }), "other.yaml", "Camera.type");
  write(dir / "resized.yaml", raw + "Camera.newWidth: 600\n");
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "resized.yaml"); }), "resized.yaml",
                         "Camera.newWidth");
  write(dir / "version.yaml", replace(raw, "\"1.0\"", "\"2.0\""));
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "version.yaml"); }), "version.yaml",
                         "File.version");
  // The shipped ORB-SLAM3-format EuRoC file is this rig.
  const StereoCalibration shipped = load_orbslam_settings(test::source_dir() / "config/camera/EuRoC_ORB-SLAM3.yaml");
  expect_same_model(StereoRectifier(shipped).camera(), m, 1e-6);
  EXPECT_LT((shipped.left.T_BS.matrix() - euroc.left.T_BS.matrix()).norm(), 1e-9);

  write(dir / "no_extrinsic.yaml", header + camera("Camera1", euroc.left) + camera("Camera2", euroc.right));
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "no_extrinsic.yaml"); }), "no_extrinsic.yaml",
                         "Stereo.T_c1_c2");
}

TEST(Calibration, ShippedKittiSettingsLoad) {
  for (const char* name : {"KITTI00-02.yaml", "KITTI03.yaml", "KITTI04-12.yaml"}) {
    const StereoCalibration calibration = load_orbslam_settings(test::source_dir() / "config" / "camera" / name);
    EXPECT_TRUE(calibration.input_rectified) << name;
    const PinholeStereo camera = StereoRectifier(calibration).camera();
    EXPECT_NEAR(camera.baseline_m, 0.537, 0.005) << name;  // KITTI's grey pair is 0.54 m apart
  }
}

// The first stereo pair of the MH01 clip with its calibration (callers skip without the shared data).
struct Mh01FirstPair {
  StereoCalibration calibration;
  cv::Mat left;
  cv::Mat right;
};

Mh01FirstPair load_mh01_first_pair() {
  const fs::path mav0 = test::shared_dataset("euroc_mh01_handheld") / "mav0";
  const std::string name = "1403636584763555584.png";
  return {load_euroc_calibration(mav0), cv::imread((mav0 / "cam0" / "data" / name).string(), cv::IMREAD_GRAYSCALE),
          cv::imread((mav0 / "cam1" / "data" / name).string(), cv::IMREAD_GRAYSCALE)};
}

TEST(Calibration, RectifiedEurocRowsAgreeOnRealImages) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const Mh01FirstPair pair = load_mh01_first_pair();
  const StereoRectifier rectifier(pair.calibration);
  const cv::Mat& left = pair.left;
  const cv::Mat& right = pair.right;
  ASSERT_FALSE(left.empty());
  cv::Mat left_rect, right_rect;
  rectifier.rectify(left, right, left_rect, right_rect);
  EXPECT_EQ(left_rect.size(), cv::Size(752, 480));
  EXPECT_EQ(right_rect.size(), cv::Size(752, 480));
  // alpha 0: no invalid (black) border in the middle rows.
  EXPECT_GT(left_rect.at<std::uint8_t>(240, 2) + left_rect.at<std::uint8_t>(240, 749), 0);
  // Wrong size is one clear error.
  const std::string error = error_of([&] { rectifier.rectify(left.colRange(0, 700), right, left_rect, right_rect); });
  expect_one_line_naming(error, "StereoRectifier", "left");
}

// The frontend rectifies the two images at once, one per thread: the same pixels as rectify().
TEST(Calibration, RectifyingTheImagesOnTwoThreadsGivesTheSamePixels) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const Mh01FirstPair pair = load_mh01_first_pair();
  const StereoRectifier rectifier(pair.calibration);
  const cv::Mat& left = pair.left;
  const cv::Mat& right = pair.right;
  ASSERT_FALSE(left.empty());
  ASSERT_FALSE(right.empty());
  cv::Mat left_rect, right_rect;
  rectifier.rectify(left, right, left_rect, right_rect);
  cv::Mat left_threaded, right_threaded;
  std::thread right_thread([&] { rectifier.rectify_right(right, right_threaded); });
  rectifier.rectify_left(left, left_threaded);
  right_thread.join();
  EXPECT_EQ(cv::norm(left_rect, left_threaded, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(right_rect, right_threaded, cv::NORM_INF), 0.0);
  // The left and right maps differ: the two outputs are not the same image.
  EXPECT_GT(cv::norm(left_threaded, right_threaded, cv::NORM_L1), 0.0);
  const std::string error = error_of([&] { rectifier.rectify_right(right.rowRange(0, 400), right_threaded); });
  expect_one_line_naming(error, "StereoRectifier", "right");
}

TEST(Calibration, MalformedEurocFilesGiveOneClearLine) {
  struct Case {
    std::string cam0;
    std::string field;
  };
  const std::vector<Case> cases = {
      {replace(kEurocCam0, "intrinsics: [458.654, 457.296, 367.215, 248.375]", "intrinsics: [458.654, 457.296]"),
       "intrinsics"},
      {replace(kEurocCam0, "resolution: [752, 480]", ""), "resolution"},
      {replace(kEurocCam0, "camera_model: pinhole", "camera_model: omni"), "camera_model"},
      {replace(kEurocCam0, "distortion_model: radial-tangential", "distortion_model: fov"), "distortion_model"},
      {replace(kEurocCam0, "0.0, 0.0, 0.0, 1.0]", "0.0, 0.0, 1.0]"), "T_BS"},
      {replace(kEurocCam0, "0.0148655429818, -0.999880929698", "2.0148655429818, -0.999880929698"), "T_BS"},
      {replace(kEurocCam0, "intrinsics: [458.654,", "intrinsics: [abc,"), "intrinsics"},
      {"T_BS: [1, 2\nfoo: {", "cam0"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const fs::path mav0 = write_euroc("bad" + std::to_string(k), cases[k].cam0, kEurocCam1);
    const std::string error = error_of([&] { load_euroc_calibration(mav0); });
    expect_one_line_naming(error, "cam0/sensor.yaml", cases[k].field);
  }
  const std::string missing = error_of([&] { load_euroc_calibration(scratch_dir("missing")); });
  expect_one_line_naming(missing, "cam0/sensor.yaml", "cannot open");
}

// A resolution no camera has would make OpenCV allocate 40 GB of rectification maps ("Failed to
// allocate 40000000000 bytes"): refused at the file, with the field named.
TEST(Calibration, ImpossibleResolutionIsRefusedBeforeOpenCv) {
  const fs::path mav0 =
      write_euroc("huge", replace(kEurocCam0, "resolution: [752, 480]", "resolution: [100000, 100000]"), kEurocCam1);
  const std::string error = error_of([&] { load_euroc_calibration(mav0); });
  expect_one_line_naming(error, "cam0/sensor.yaml", "resolution: image size 100000 px: expected 1..8192 px per side");
  // The same camera built in code (as from a message) is refused by the rectifier, naming its source.
  StereoCalibration calibration = load_euroc_calibration(write_euroc("ok", kEurocCam0, kEurocCam1));
  calibration.left.width_px = 100000;
  calibration.left.height_px = 100000;
  calibration.source = "huge rig";
  EXPECT_EQ(error_of([&] { StereoRectifier rectifier(calibration); }),
            "huge rig: left camera: image size 100000x100000: expected 1..8192 px per side");
}

// A nan anywhere is named where it is, not reported by a later check it throws off. Before: a nan
// distortion coefficient came out as "right camera: expected it to the right of the left camera".
TEST(Calibration, ANanIsNamedWhereItIs) {
  const std::string text = replace(kEurocCam1, "[-0.28368365,", "[.nan,");
  ASSERT_NE(text, kEurocCam1);
  const std::string error = error_of([&] { load_euroc_calibration(write_euroc("nan", kEurocCam0, text)); });
  expect_one_line_naming(error, "cam1/sensor.yaml", "distortion_coefficients: expected finite numbers, item 0 is nan");
  // The same from a message (the frontend's calibration topic): the rectifier names the field.
  StereoCalibration calibration = load_euroc_calibration(write_euroc("ok_nan", kEurocCam0, kEurocCam1));
  calibration.right.distortion[1] = std::numeric_limits<double>::quiet_NaN();
  calibration.source = "topic rig";
  EXPECT_EQ(error_of([&] { StereoRectifier rectifier(calibration); }),
            "topic rig: right camera distortion coefficient 1: expected finite numbers, got a nan or inf");
  calibration.right.distortion[1] = 0.0;
  calibration.left.T_BS.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([&] { StereoRectifier rectifier(calibration); }),
            "topic rig: left camera T_BS: expected finite numbers, got a nan or inf");
}

TEST(Calibration, MalformedKittiAndOrbSlamFilesGiveOneClearLine) {
  const fs::path dir = scratch_dir("bad_formats");
  write(dir / "short.txt", "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1\nP1: 1 2 3\n");
  expect_one_line_naming(error_of([&] { load_kitti_calibration(dir / "short.txt", 1241, 376); }), "short.txt", "P0");
  write(dir / "no_p1.txt", "P0: 718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0\n");
  expect_one_line_naming(error_of([&] { load_kitti_calibration(dir / "no_p1.txt", 1241, 376); }), "no_p1.txt", "P1");

  const std::string good =
      "%YAML:1.0\nCamera.fx: 718.856\nCamera.fy: 718.856\nCamera.cx: 607.1928\n"
      "Camera.cy: 185.2157\nCamera.width: 1241\nCamera.height: 376\nCamera.bf: 386.1448\n";
  write(dir / "good.yaml", good);
  EXPECT_NO_THROW(load_orbslam_settings(dir / "good.yaml"));
  write(dir / "no_bf.yaml", replace(good, "Camera.bf: 386.1448\n", ""));
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "no_bf.yaml"); }), "no_bf.yaml", "Camera.bf");
  write(dir / "text_fx.yaml", replace(good, "Camera.fx: 718.856", "Camera.fx: seven"));
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "text_fx.yaml"); }), "text_fx.yaml", "Camera.fx");
  write(dir / "distorted.yaml", good + "Camera.k1: -0.2\n");
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "distorted.yaml"); }), "distorted.yaml",
                         "Camera.k1");
  write(dir / "bad_k.yaml",
        good + "LEFT.K: !!opencv-matrix\n   rows: 2\n   cols: 2\n   dt: d\n   data: [1, 0, 0, 1]\n");
  expect_one_line_naming(error_of([&] { load_orbslam_settings(dir / "bad_k.yaml"); }), "bad_k.yaml", "LEFT.K");
}

}  // namespace
}  // namespace heslam
