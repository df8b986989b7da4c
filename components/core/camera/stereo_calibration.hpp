// Raw (unrectified) stereo calibration and its loaders for the formats users already have:
// EuRoC ASL sensor.yaml pairs, KITTI odometry calib.txt, and ORB-SLAM2 / ORB-SLAM3 stereo settings files.
// Lenses: pinhole with radial-tangential distortion, or equidistant (Kannala-Brandt) fisheye.
//
// Every loader throws std::runtime_error whose what() is one line naming the file and the field.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"

namespace heslam {

// radtan: k1 k2 p1 p2 [k3]; equidistant (Kannala-Brandt fisheye, camera/equidistant.hpp): k1 k2 k3 k4.
enum class DistortionModel { kNone, kRadialTangential, kEquidistant };

// "none", "radial-tangential" or "equidistant" (the EuRoC / Kalibr spelling).
const char* to_string(DistortionModel model);

// One raw camera of the rig.
struct CameraModel {
  int width_px = 0;
  int height_px = 0;
  double fx_px = 0;
  double fy_px = 0;
  double cx_px = 0;
  double cy_px = 0;
  DistortionModel distortion_model = DistortionModel::kNone;
  std::vector<double> distortion;  // k1 k2 p1 p2 [k3] (radtan) or k1 k2 k3 k4 (equidistant)
  Pose3 T_BS = Pose3::Identity();  // sensor (this camera) -> body
};

// Rectifying rotations and projections given explicitly (ORB-SLAM2 settings LEFT.R/P, RIGHT.R/P).
struct ExplicitRectification {
  Eigen::Matrix3d R_left = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R_right = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 3, 4> P_left = Eigen::Matrix<double, 3, 4>::Zero();
  Eigen::Matrix<double, 3, 4> P_right = Eigen::Matrix<double, 3, 4>::Zero();
};

struct StereoCalibration {
  // Uses `rect` (p_rect_l = R_left p_l, p_rect_r = R_right p_r, p_rect_r = p_rect_l - baseline e_x, the
  // body the left camera): sets right.T_BS from it and keeps it as explicit_rectification.
  void set_explicit_rectification(const ExplicitRectification& rect, double baseline_m);

  CameraModel left;
  CameraModel right;
  // True for KITTI calib.txt and ORB-SLAM2 settings without LEFT.*: the images are already rectified
  // and `left` holds the rectified intrinsics, `right.T_BS` the baseline along +x.
  bool input_rectified = false;
  std::optional<ExplicitRectification> explicit_rectification;
  double rate_hz = 0.0;  // 0 = unknown
  std::string source;    // file(s) it was read from

  // Left camera -> right camera: p_right = T_rl() * p_left.
  Pose3 T_rl() const { return right.T_BS.inverse() * left.T_BS; }
};

// EuRoC ASL layout: reads mav0_dir/cam0/sensor.yaml (left) and mav0_dir/cam1/sensor.yaml (right);
// distortion_model radial-tangential (radtan), equidistant (4 coefficients, as TUM-VI) or none.
StereoCalibration load_euroc_calibration(const std::filesystem::path& mav0_dir);

// KITTI odometry calib.txt: rectified projections P0 (left) and P1 (right); the image size is not in
// the file, so the caller passes it (1241x376 for sequences 00-02, 1226x370 for 04-12).
StereoCalibration load_kitti_calibration(const std::filesystem::path& calib_txt, int width_px, int height_px);

// ORB-SLAM2 stereo settings: Camera.fx/fy/cx/cy/width/height/bf (+ Camera.fps), and optionally
// LEFT.K/D/R/P, RIGHT.K/D/R/P (+ LEFT.width/height) for raw images that must be rectified.
// ORB-SLAM3 stereo settings (File.version "1.0", Camera.type "PinHole"): Camera1.fx/fy/cx/cy[/k1 k2 p1
// p2 [k3]], Camera.width/height (+ Camera.fps), and either Camera2.* + Stereo.T_c1_c2 (raw pair, camera
// 2 -> camera 1) or Stereo.b (rectified pair); IMU.T_b_c1, when present, is the left camera's T_BS.
// Camera.type "KannalaBrandt8" (fisheye, as its TUM-VI files): Camera1/2.k1 k2 k3 k4 are required, the
// pair is raw (Camera2.* + Stereo.T_c1_c2); Camera1/2.overlappingBegin/End are ORB-SLAM3's own and
// ignored (heslam rectifies the whole pair).
StereoCalibration load_orbslam_settings(const std::filesystem::path& settings_yaml);

}  // namespace heslam
