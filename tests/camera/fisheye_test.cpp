// The equidistant (Kannala-Brandt) fisheye model with exact geometry: a 3D point projected and back,
// agreement with OpenCV's cv::fisheye, rectification of a synthetic fisheye pair (blobs at known 3D
// points drawn into raw images, rectified, found again on one row at disparity f b / z), and the
// three calibration formats that carry it (EuRoC sensor.yaml, Kalibr camchain, ORB-SLAM3
// KannalaBrandt8) read into the same calibration; an unknown model is one line naming file and field.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>

#include "components/core/camera/equidistant.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "test_support.hpp"
#include "tools/camera/camera_calibration.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// TUM-VI cam0's lens coefficients on a 752x480 image at fx = fy = 330 (config/synth/cameras/fisheye.yaml).
const std::vector<double> kLens{0.003482389402, 0.000715034845, -0.002053236141, 0.000202936736};

CameraModel fisheye_camera(double fx, double fy, double cx, double cy) {
  CameraModel camera;
  camera.width_px = 752;
  camera.height_px = 480;
  camera.fx_px = fx;
  camera.fy_px = fy;
  camera.cx_px = cx;
  camera.cy_px = cy;
  camera.distortion_model = DistortionModel::kEquidistant;
  camera.distortion = kLens;
  return camera;
}

// A fisheye pair: the right camera 0.11 m along +x, turned by a degree and a bit (so rectification has
// something to undo), its own intrinsics.
StereoCalibration fisheye_pair() {
  StereoCalibration calibration;
  calibration.left = fisheye_camera(330.0, 331.0, 375.5, 239.5);
  calibration.right = fisheye_camera(329.0, 330.5, 377.0, 241.0);
  calibration.right.distortion = {0.0031, 0.0009, -0.0019, 0.00018};
  Pose3 T_lr = Pose3::Identity();  // right camera -> left camera = right.T_BS (body = left camera)
  T_lr.linear() =
      (Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.01, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(0.005, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  T_lr.translation() = Eigen::Vector3d(0.11, 0.002, -0.001);
  calibration.right.T_BS = T_lr;
  calibration.rate_hz = 20.0;
  calibration.source = "fisheye_pair";
  return calibration;
}

Eigen::Vector2d project(const CameraModel& c, const Eigen::Vector3d& p) {
  const Eigen::Vector2d xd = equidistant_distort_ray(p, c.distortion);
  return {c.fx_px * xd.x() + c.cx_px, c.fy_px * xd.y() + c.cy_px};
}

Eigen::Vector3d unproject(const CameraModel& c, const Eigen::Vector2d& pixel) {
  return equidistant_undistort_ray({(pixel.x() - c.cx_px) / c.fx_px, (pixel.y() - c.cy_px) / c.fy_px}, c.distortion);
}

TEST(EquidistantModel, PointProjectedAndBackGivesItsRay) {
  const CameraModel camera = fisheye_camera(330.0, 331.0, 375.5, 239.5);
  std::mt19937 random(35);
  std::uniform_real_distribution<double> angle(0.0, 100.0 * M_PI / 180.0);  // beyond 90 deg too
  std::uniform_real_distribution<double> azimuth(-M_PI, M_PI);
  std::uniform_real_distribution<double> range(0.2, 30.0);
  double worst = 0.0;
  for (int i = 0; i < 10000; ++i) {
    const double theta = angle(random), phi = azimuth(random);
    const Eigen::Vector3d ray(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    const Eigen::Vector3d point = range(random) * ray;
    worst = std::max(worst, (unproject(camera, project(camera, point)) - ray).norm());
  }
  EXPECT_LT(worst, 1e-9);
  // The optical axis and a point straight ahead.
  EXPECT_EQ(project(camera, {0.0, 0.0, 2.0}), Eigen::Vector2d(375.5, 239.5));
  EXPECT_LT((unproject(camera, {375.5, 239.5}) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
}

TEST(EquidistantModel, AgreesWithOpenCvFisheye) {
  const CameraModel camera = fisheye_camera(330.0, 331.0, 375.5, 239.5);
  std::vector<cv::Point3d> points;
  std::vector<Eigen::Vector2d> ours;
  for (double x = -3.0; x <= 3.0; x += 0.5) {
    for (double y = -2.0; y <= 2.0; y += 0.5) {
      points.emplace_back(x, y, 1.0);
      ours.push_back(project(camera, {x, y, 1.0}));
    }
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
  std::vector<cv::Point2d> theirs;
  cv::fisheye::projectPoints(points, theirs, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, kLens);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR(ours[i].x(), theirs[i].x, 1e-9);
    EXPECT_NEAR(ours[i].y(), theirs[i].y, 1e-9);
  }
}

// A Gaussian blob (sigma 1.2 px, peak 200) at a sub-pixel position of an 8-bit image.
void draw_blob(cv::Mat& image, const Eigen::Vector2d& at) {
  constexpr double kSigma = 1.2;
  const int c0 = static_cast<int>(std::floor(at.x())), r0 = static_cast<int>(std::floor(at.y()));
  for (int r = r0 - 5; r <= r0 + 6; ++r) {
    for (int c = c0 - 5; c <= c0 + 6; ++c) {
      if (r < 0 || c < 0 || r >= image.rows || c >= image.cols) continue;
      const double d2 = (c - at.x()) * (c - at.x()) + (r - at.y()) * (r - at.y());
      const double value = image.at<std::uint8_t>(r, c) + 200.0 * std::exp(-d2 / (2 * kSigma * kSigma));
      image.at<std::uint8_t>(r, c) = cv::saturate_cast<std::uint8_t>(value);
    }
  }
}

// Intensity-weighted centre of the pixels within 5 px of `near` (the image is black elsewhere).
Eigen::Vector2d centroid(const cv::Mat& image, const Eigen::Vector2d& near) {
  double sum = 0.0, sx = 0.0, sy = 0.0;
  const int c0 = static_cast<int>(std::lround(near.x())), r0 = static_cast<int>(std::lround(near.y()));
  for (int r = r0 - 5; r <= r0 + 5; ++r) {
    for (int c = c0 - 5; c <= c0 + 5; ++c) {
      if (r < 0 || c < 0 || r >= image.rows || c >= image.cols) continue;
      const double w = image.at<std::uint8_t>(r, c);
      sum += w;
      sx += w * c;
      sy += w * r;
    }
  }
  return sum > 0.0 ? Eigen::Vector2d(sx / sum, sy / sum) : Eigen::Vector2d(-1e9, -1e9);
}

TEST(FisheyeRectification, KnownPointsLandOnOneRowAtTheirDisparity) {
  const StereoCalibration calibration = fisheye_pair();
  const StereoRectifier rectifier(calibration);
  const PinholeStereo& rect = rectifier.camera();
  EXPECT_NEAR(rect.baseline_m, calibration.T_rl().translation().norm(), 1e-9);
  EXPECT_GT(rect.fx_px, 100.0);
  // p_rect = R1 p_left: the rectified left camera is the left camera turned (left.T_BS is identity).
  const Eigen::Matrix3d R1 = rectifier.T_B_rect().linear().transpose();
  const Pose3 T_rl = calibration.T_rl();

  // Blobs 60 px apart over the whole rectified image, at depths 0.8 m to 12 m (known 3D points).
  struct Point {
    Eigen::Vector3d rect;  // in the rectified left camera
    Eigen::Vector2d left, right;
  };
  std::vector<Point> points;
  const std::vector<double> depths{0.8, 1.5, 3.0, 6.0, 12.0};
  int k = 0;
  for (double v = 30.0; v < rect.height_px - 30.0; v += 60.0) {
    for (double u = 40.0; u < rect.width_px - 40.0; u += 60.0, ++k) {
      const double z = depths[static_cast<std::size_t>(k) % depths.size()];
      const Eigen::Vector3d p_rect((u + 0.37 - rect.cx_px) / rect.fx_px * z, (v + 0.21 - rect.cy_px) / rect.fy_px * z,
                                   z);
      const Eigen::Vector3d p_left = R1.transpose() * p_rect;
      const Eigen::Vector3d p_right = T_rl * p_left;
      points.push_back({p_rect, project(calibration.left, p_left), project(calibration.right, p_right)});
    }
  }
  ASSERT_GT(points.size(), 60u);
  cv::Mat left_raw = cv::Mat::zeros(480, 752, CV_8UC1), right_raw = left_raw.clone();
  for (const Point& p : points) {
    draw_blob(left_raw, p.left);
    draw_blob(right_raw, p.right);
  }
  cv::Mat left_rect, right_rect;
  rectifier.rectify(left_raw, right_raw, left_rect, right_rect);
  cv::Mat left_fast, right_fast;
  rectifier.rectify_left(left_raw, left_fast);
  rectifier.rectify_right(right_raw, right_fast);
  EXPECT_EQ(cv::norm(left_rect, left_fast, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(right_rect, right_fast, cv::NORM_INF), 0.0);

  double worst_dy = 0.0, worst_disparity = 0.0, worst_position = 0.0;
  int measured = 0;
  for (const Point& p : points) {
    const Eigen::Vector2d expected_left(rect.fx_px * p.rect.x() / p.rect.z() + rect.cx_px,
                                        rect.fy_px * p.rect.y() / p.rect.z() + rect.cy_px);
    const double disparity = rect.fx_px * rect.baseline_m / p.rect.z();
    const Eigen::Vector2d expected_right = expected_left - Eigen::Vector2d(disparity, 0.0);
    if (expected_right.x() < 8.0) continue;  // its right blob is outside the rectified right image
    const Eigen::Vector2d left = centroid(left_rect, expected_left);
    const Eigen::Vector2d right = centroid(right_rect, expected_right);
    worst_dy = std::max(worst_dy, std::abs(left.y() - right.y()));
    worst_disparity = std::max(worst_disparity, std::abs((left.x() - right.x()) - disparity));
    worst_position = std::max(worst_position, (left - expected_left).norm());
    ++measured;
  }
  std::printf(
      "[ figures  ] fisheye rectification: %d blobs, fx %.2f px, worst |dy| %.3f px, worst disparity "
      "error %.3f px, worst position error %.3f px\n",
      measured, rect.fx_px, worst_dy, worst_disparity, worst_position);
  EXPECT_GT(measured, 50);
  EXPECT_LT(worst_dy, 0.5);
  EXPECT_LT(worst_disparity, 0.5);
  EXPECT_LT(worst_position, 0.5);
}

TEST(FisheyeRectification, MixedLensPairIsOneLine) {
  StereoCalibration calibration = fisheye_pair();
  calibration.right.distortion_model = DistortionModel::kRadialTangential;
  calibration.right.distortion = {0.0, 0.0, 0.0, 0.0};
  try {
    const StereoRectifier rectifier(calibration);
    FAIL() << "a fisheye left and a pinhole right camera rectified";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()),
              "fisheye_pair: left camera equidistant, right camera radial-tangential: expected both equidistant "
              "(fisheye) or neither");
  }
  calibration = fisheye_pair();
  calibration.left.distortion.pop_back();
  try {
    const StereoRectifier rectifier(calibration);
    FAIL() << "3 equidistant coefficients taken";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()),
              "fisheye_pair: left camera distortion: expected 4 equidistant coefficients k1 k2 k3 k4, got 3");
  }
}

// ---- the three file formats -------------------------------------------------------------------

std::string rows_of(const Pose3& pose, const std::string& indent, bool brackets) {
  std::string text;
  for (int r = 0; r < 4; ++r) {
    char row[200];
    const auto& m = pose.matrix();
    std::snprintf(row, sizeof row, brackets ? "%s- [%.17g, %.17g, %.17g, %.17g]\n" : "%s%.17g, %.17g, %.17g, %.17g%s",
                  indent.c_str(), m(r, 0), m(r, 1), m(r, 2), m(r, 3), brackets ? "" : (r == 3 ? "" : ", "));
    text += row;
  }
  return text;
}

std::string numbers(const std::vector<double>& values) {
  std::string text;
  for (double v : values) {
    char number[40];
    std::snprintf(number, sizeof number, "%.17g", v);
    text += (text.empty() ? "" : ", ") + std::string(number);
  }
  return text;
}

std::string euroc_sensor_yaml(const CameraModel& c, const std::string& model = "equidistant") {
  return "sensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [" + rows_of(c.T_BS, "", false) +
         "]\nrate_hz: 20\nresolution: [" + std::to_string(c.width_px) + ", " + std::to_string(c.height_px) +
         "]\ncamera_model: pinhole\nintrinsics: [" + numbers({c.fx_px, c.fy_px, c.cx_px, c.cy_px}) +
         "]\ndistortion_model: " + model + "\ndistortion_coefficients: [" + numbers(c.distortion) + "]\n";
}

std::string kalibr_camera(const CameraModel& c, const std::string& model = "equidistant") {
  return "  camera_model: pinhole\n  distortion_coeffs: [" + numbers(c.distortion) + "]\n  distortion_model: " + model +
         "\n  intrinsics: [" + numbers({c.fx_px, c.fy_px, c.cx_px, c.cy_px}) + "]\n  resolution: [" +
         std::to_string(c.width_px) + ", " + std::to_string(c.height_px) + "]\n";
}

// kalibr_calibrate_cameras' camchain (no IMU: the left camera is the body).
std::string kalibr_camchain(const StereoCalibration& s, const std::string& model = "equidistant") {
  return "cam0:\n  cam_overlaps: [1]\n" + kalibr_camera(s.left, model) + "  rostopic: /cam0/image_raw\ncam1:\n" +
         "  T_cn_cnm1:\n" + rows_of(s.T_rl(), "  ", true) + "  cam_overlaps: [0]\n" + kalibr_camera(s.right, model) +
         "  rostopic: /cam1/image_raw\n";
}

// ORB-SLAM3's KannalaBrandt8 stereo settings, as its Examples/Stereo/TUM-VI.yaml.
std::string orbslam3_kannala_brandt(const StereoCalibration& s, const std::string& type = "KannalaBrandt8") {
  std::string text = "%YAML:1.0\nFile.version: \"1.0\"\nCamera.type: \"" + type + "\"\n";
  for (const auto& [name, c] : {std::pair{"Camera1", &s.left}, std::pair{"Camera2", &s.right}}) {
    const std::string n = name;
    const std::vector<double> values{c->fx_px, c->fy_px, c->cx_px, c->cy_px};
    const char* keys[] = {".fx", ".fy", ".cx", ".cy"};
    for (int i = 0; i < 4; ++i) text += n + keys[i] + ": " + numbers({values[static_cast<std::size_t>(i)]}) + "\n";
    for (int i = 0; i < 4; ++i) {
      text += n + ".k" + std::to_string(i + 1) + ": " + numbers({c->distortion[static_cast<std::size_t>(i)]}) + "\n";
    }
    text += n + ".overlappingBegin: 0\n" + n + ".overlappingEnd: 751\n";
  }
  text += "Camera.width: 752\nCamera.height: 480\nCamera.fps: 20\nCamera.RGB: 1\nStereo.ThDepth: 40.0\n";
  text += "Stereo.T_c1_c2: !!opencv-matrix\n  rows: 4\n  cols: 4\n  dt: d\n  data: [" +
          rows_of(s.right.T_BS, "", false) + "]\n";
  return text;
}

void write_text(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

void expect_same_calibration(const StereoCalibration& a, const StereoCalibration& b, const std::string& what) {
  SCOPED_TRACE(what);
  for (const auto& [x, y] : {std::pair{&a.left, &b.left}, std::pair{&a.right, &b.right}}) {
    EXPECT_EQ(y->distortion_model, DistortionModel::kEquidistant);
    EXPECT_EQ(x->distortion_model, y->distortion_model);
    EXPECT_EQ(x->width_px, y->width_px);
    EXPECT_EQ(x->height_px, y->height_px);
    EXPECT_EQ(x->fx_px, y->fx_px);
    EXPECT_EQ(x->fy_px, y->fy_px);
    EXPECT_EQ(x->cx_px, y->cx_px);
    EXPECT_EQ(x->cy_px, y->cy_px);
    EXPECT_EQ(x->distortion, y->distortion);
  }
  EXPECT_LT((a.T_rl().matrix() - b.T_rl().matrix()).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_FALSE(b.input_rectified);
  const PinholeStereo ra = StereoRectifier(a).camera(), rb = StereoRectifier(b).camera();
  EXPECT_NEAR(ra.fx_px, rb.fx_px, 1e-9);
  EXPECT_NEAR(ra.cx_px, rb.cx_px, 1e-9);
  EXPECT_NEAR(ra.cy_px, rb.cy_px, 1e-9);
  EXPECT_NEAR(ra.baseline_m, rb.baseline_m, 1e-12);
}

class FisheyeFormats : public ::testing::Test {
 protected:
  const StereoCalibration truth_ = fisheye_pair();
  const test::ScratchDir dir_{"fisheye_formats"};
};

TEST_F(FisheyeFormats, EurocKalibrAndOrbSlam3ReadIntoTheSameCalibration) {
  const fs::path mav0 = dir_.path() / "mav0";
  fs::create_directories(mav0 / "cam0");
  fs::create_directories(mav0 / "cam1");
  write_text(mav0 / "cam0/sensor.yaml", euroc_sensor_yaml(truth_.left));
  write_text(mav0 / "cam1/sensor.yaml", euroc_sensor_yaml(truth_.right));
  write_text(dir_.path() / "camchain.yaml", kalibr_camchain(truth_));
  write_text(dir_.path() / "tum_vi.yaml", orbslam3_kannala_brandt(truth_));
  expect_same_calibration(truth_, load_euroc_calibration(mav0), "EuRoC sensor.yaml");
  expect_same_calibration(truth_, load_camera_calibration(mav0), "heslam-camera, EuRoC folder");
  ASSERT_EQ(detect_calibration_format(dir_.path() / "camchain.yaml"), CalibrationFormat::kKalibr);
  expect_same_calibration(truth_, load_camera_calibration(dir_.path() / "camchain.yaml"), "Kalibr camchain");
  expect_same_calibration(truth_, load_orbslam_settings(dir_.path() / "tum_vi.yaml"), "ORB-SLAM3 KannalaBrandt8");
  expect_same_calibration(truth_, load_camera_calibration(dir_.path() / "tum_vi.yaml"), "heslam-camera, ORB-SLAM3");
}

std::string error_of(const std::function<void()>& load) {
  try {
    load();
  } catch (const std::exception& error) {
    return error.what();
  }
  return "no error";
}

TEST_F(FisheyeFormats, UnknownModelIsOneLineNamingFileAndField) {
  const fs::path mav0 = dir_.path() / "mav0";
  fs::create_directories(mav0 / "cam0");
  fs::create_directories(mav0 / "cam1");
  write_text(mav0 / "cam0/sensor.yaml", euroc_sensor_yaml(truth_.left, "fov"));
  write_text(mav0 / "cam1/sensor.yaml", euroc_sensor_yaml(truth_.right));
  EXPECT_EQ(error_of([&] { load_euroc_calibration(mav0); }),
            (mav0 / "cam0/sensor.yaml").string() +
                ": distortion_model: expected 'radial-tangential', 'equidistant' or 'none', got 'fov'");
  // Equidistant with 5 coefficients (a radtan list under the fisheye's name).
  CameraModel five = truth_.left;
  five.distortion.push_back(0.0);
  write_text(mav0 / "cam0/sensor.yaml", euroc_sensor_yaml(five));
  EXPECT_EQ(error_of([&] { load_euroc_calibration(mav0); }),
            (mav0 / "cam0/sensor.yaml").string() + ": distortion_coefficients: expected 4 numbers, got 5");

  write_text(dir_.path() / "camchain.yaml", kalibr_camchain(truth_, "fov"));
  EXPECT_EQ(error_of([&] { load_camera_calibration(dir_.path() / "camchain.yaml"); }),
            (dir_.path() / "camchain.yaml").string() +
                ": cam0.distortion_model: 'fov' is not supported (radtan, equidistant or none)");

  const fs::path settings = dir_.path() / "settings.yaml";
  write_text(settings, orbslam3_kannala_brandt(truth_, "Rectified"));
  EXPECT_EQ(error_of([&] { load_orbslam_settings(settings); }),
            settings.string() +
                ": Camera.type: expected \"PinHole\" or \"KannalaBrandt8\" (heslam rectifies pinhole radial-tangential "
                "and equidistant fisheye cameras; got 'Rectified')");
  std::string no_k4 = orbslam3_kannala_brandt(truth_);
  no_k4.erase(no_k4.find("Camera2.k4"), no_k4.find('\n', no_k4.find("Camera2.k4")) - no_k4.find("Camera2.k4") + 1);
  write_text(settings, no_k4);
  EXPECT_EQ(error_of([&] { load_orbslam_settings(settings); }),
            settings.string() + ": Camera2.k4: missing (expected a number)");
}

}  // namespace
}  // namespace heslam
