// Loading a live rig's calibration: EuRoC folders and ORB-SLAM settings through the core loaders,
// Kalibr camchains here (cv::FileStorage after fixing the YAML dialect).
#include "tools/camera/camera_calibration.hpp"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

namespace heslam {

namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot read the calibration file");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The EuRoC mav0 folder: `path` itself or path/mav0.
fs::path euroc_mav0(const fs::path& path) {
  if (fs::exists(path / "cam0" / "sensor.yaml")) return path;
  if (fs::exists(path / "mav0" / "cam0" / "sensor.yaml")) return path / "mav0";
  throw std::runtime_error(path.string() +
                           ": a calibration folder must be an EuRoC mav0/ (cam0/sensor.yaml, cam1/sensor.yaml) "
                           "or hold one");
}

bool has_top_level_cam0(const std::string& text) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("cam0:", 0) == 0) return true;
  }
  return false;
}

std::vector<double> numbers(const cv::FileNode& node, const std::string& where, std::size_t count) {
  if (!node.isSeq() || node.size() != count) {
    throw std::runtime_error(where + ": expected a list of " + std::to_string(count) + " numbers");
  }
  std::vector<double> values;
  for (const cv::FileNode& item : node) {
    if (!item.isReal() && !item.isInt()) throw std::runtime_error(where + ": expected numbers");
    values.push_back(item.real());
  }
  return values;
}

Pose3 matrix4(const cv::FileNode& node, const std::string& where) {
  if (!node.isSeq() || node.size() != 4) throw std::runtime_error(where + ": expected 4 rows of 4 numbers");
  Eigen::Matrix4d matrix;
  int row = 0;
  for (const cv::FileNode& line : node) {
    const std::vector<double> values = numbers(line, where + " row " + std::to_string(row + 1), 4);
    for (int col = 0; col < 4; ++col) matrix(row, col) = values[static_cast<std::size_t>(col)];
    ++row;
  }
  constexpr double kTolerance = 1e-6;  // a rotation printed with fewer digits is still one
  const Eigen::Matrix3d rotation = matrix.topLeftCorner<3, 3>();
  if ((rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > kTolerance ||
      std::abs(rotation.determinant() - 1.0) > kTolerance ||
      (matrix.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 0) {
    throw std::runtime_error(where + ": not a rigid transform (rotation not orthonormal, or last row not 0 0 0 1)");
  }
  Pose3 pose = Pose3::Identity();
  pose.matrix() = matrix;
  return pose;
}

CameraModel kalibr_camera(const cv::FileNode& node, const std::string& where) {
  if (node.empty() || !node.isMap()) throw std::runtime_error(where + ": missing");
  const std::string model = node["camera_model"].empty() ? "" : node["camera_model"].string();
  if (model != "pinhole") {
    throw std::runtime_error(where + ".camera_model: '" + model + "' is not supported (pinhole only)");
  }
  CameraModel camera;
  const std::vector<double> intrinsics = numbers(node["intrinsics"], where + ".intrinsics", 4);
  camera.fx_px = intrinsics[0];
  camera.fy_px = intrinsics[1];
  camera.cx_px = intrinsics[2];
  camera.cy_px = intrinsics[3];
  const std::vector<double> resolution = numbers(node["resolution"], where + ".resolution", 2);
  camera.width_px = static_cast<int>(resolution[0]);
  camera.height_px = static_cast<int>(resolution[1]);
  if (camera.width_px <= 0 || camera.height_px <= 0 || camera.fx_px <= 0 || camera.fy_px <= 0) {
    throw std::runtime_error(where + ": resolution and focal lengths must be positive");
  }
  const std::string distortion = node["distortion_model"].empty() ? "none" : node["distortion_model"].string();
  if (distortion == "radtan") {
    camera.distortion_model = DistortionModel::kRadialTangential;
    camera.distortion = numbers(node["distortion_coeffs"], where + ".distortion_coeffs", 4);
  } else if (distortion == "equidistant") {
    camera.distortion_model = DistortionModel::kEquidistant;
    camera.distortion = numbers(node["distortion_coeffs"], where + ".distortion_coeffs", 4);
  } else if (distortion == "none") {
    camera.distortion_model = DistortionModel::kNone;
  } else {
    throw std::runtime_error(where + ".distortion_model: '" + distortion.substr(0, 40) +
                             "' is not supported (radtan, equidistant or none)");
  }
  return camera;
}

}  // namespace

std::string kalibr_yaml_for_opencv(const std::string& text) {
  std::ostringstream out;
  if (text.rfind("%YAML", 0) != 0) out << "%YAML:1.0\n---\n";
  std::istringstream lines(text);
  int key_indent = -1;  // indentation of the last `key:` without a value; its `- ` items go deeper
  for (std::string line; std::getline(lines, line);) {
    const std::size_t first = line.find_first_not_of(' ');
    if (first == std::string::npos) {
      out << line << '\n';
      continue;
    }
    const int indent = static_cast<int>(first);
    if (line.compare(first, 2, "- ") == 0 && indent == key_indent) {
      out << "  " << line << '\n';
      continue;
    }
    const std::size_t end = line.find_last_not_of(" \t\r");
    key_indent = (line[end] == ':' && line[first] != '#') ? indent : -1;
    out << line << '\n';
  }
  return out.str();
}

CalibrationFormat detect_calibration_format(const fs::path& path) {
  if (fs::is_directory(path)) return CalibrationFormat::kEuroc;
  if (!fs::exists(path)) throw std::runtime_error(path.string() + ": no such calibration file or folder");
  return has_top_level_cam0(read_text(path)) ? CalibrationFormat::kKalibr : CalibrationFormat::kOrbSlam;
}

const char* to_string(CalibrationFormat format) {
  switch (format) {
    case CalibrationFormat::kEuroc: return "EuRoC sensor.yaml";
    case CalibrationFormat::kKalibr: return "Kalibr camchain";
    case CalibrationFormat::kOrbSlam: return "ORB-SLAM settings";
  }
  return "?";
}

StereoCalibration load_kalibr_camchain(const fs::path& file) {
  const std::string where = file.string();
  cv::FileStorage storage;
  try {
    storage.open(kalibr_yaml_for_opencv(read_text(file)), cv::FileStorage::READ | cv::FileStorage::MEMORY);
  } catch (const cv::Exception& failure) {
    throw std::runtime_error(where + ": not a YAML file cv::FileStorage can read (" + failure.err + ")");
  }
  if (!storage.isOpened()) throw std::runtime_error(where + ": not a YAML file cv::FileStorage can read");
  StereoCalibration calibration;
  calibration.left = kalibr_camera(storage["cam0"], where + ": cam0");
  calibration.right = kalibr_camera(storage["cam1"], where + ": cam1");
  if (!storage["cam0"]["T_cam_imu"].empty()) {
    calibration.left.T_BS = matrix4(storage["cam0"]["T_cam_imu"], where + ": cam0.T_cam_imu").inverse();
  }
  if (storage["cam1"]["T_cn_cnm1"].empty()) throw std::runtime_error(where + ": cam1.T_cn_cnm1: missing");
  const Pose3 T_rl = matrix4(storage["cam1"]["T_cn_cnm1"], where + ": cam1.T_cn_cnm1");
  calibration.right.T_BS = calibration.left.T_BS * T_rl.inverse();
  if (calibration.left.width_px != calibration.right.width_px ||
      calibration.left.height_px != calibration.right.height_px) {
    throw std::runtime_error(where + ": cam0 and cam1 resolutions differ");
  }
  calibration.source = where;
  return calibration;
}

StereoCalibration load_camera_calibration(const fs::path& path) {
  switch (detect_calibration_format(path)) {
    case CalibrationFormat::kEuroc: return load_euroc_calibration(euroc_mav0(path));
    case CalibrationFormat::kKalibr: return load_kalibr_camchain(path);
    case CalibrationFormat::kOrbSlam: return load_orbslam_settings(path);
  }
  throw std::logic_error("unknown calibration format");
}

}  // namespace heslam
