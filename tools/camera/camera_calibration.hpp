// heslam-camera's --calibration: the raw stereo calibration of a live rig from the files users have.
//   an EuRoC ASL folder (mav0/ or the folder holding it): cam0/sensor.yaml, cam1/sensor.yaml
//   a Kalibr camchain YAML (cam0/cam1: intrinsics, distortion_coeffs, resolution, cam1.T_cn_cnm1)
//   an ORB-SLAM2 / ORB-SLAM3 stereo settings file (load_orbslam_settings)
// DDS-free. Every loader throws std::runtime_error with one line naming the file and the field.
#pragma once

#include <filesystem>
#include <string>

#include "components/core/camera/stereo_calibration.hpp"

namespace heslam {

// Which of the three the path is, by its shape: a folder is EuRoC, a YAML file with a top-level
// `cam0:` map is a Kalibr camchain, any other file an ORB-SLAM settings file.
enum class CalibrationFormat { kEuroc, kKalibr, kOrbSlam };
CalibrationFormat detect_calibration_format(const std::filesystem::path& path);
const char* to_string(CalibrationFormat format);

StereoCalibration load_camera_calibration(const std::filesystem::path& path);

// Kalibr camchain (kalibr_calibrate_cameras' camchain-*.yaml): pinhole cameras with radtan (or no)
// distortion. cam1.T_cn_cnm1 maps cam0 points into cam1 (= T_rl); cam0.T_cam_imu, when present, is
// the inverse of cam0's T_BS (otherwise cam0 is the body frame). Fisheye (equidistant) and other
// camera models are refused by name. cv::FileStorage reads the file after two textual fixes Kalibr's
// PyYAML output needs: the %YAML:1.0 header and sequence items indented below their key.
StereoCalibration load_kalibr_camchain(const std::filesystem::path& file);

// The two fixes above, exposed for the tests.
std::string kalibr_yaml_for_opencv(const std::string& text);

}  // namespace heslam
