// Loaders for EuRoC sensor.yaml pairs, KITTI calib.txt and ORB-SLAM2 / ORB-SLAM3 stereo settings.
#include "components/core/camera/stereo_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "components/core/camera/image_limits.hpp"

namespace heslam {
namespace {

// EuRoC sensor.yaml files are plain YAML without the "%YAML:1.0" line cv::FileStorage insists on.
constexpr const char* kOpenCvYamlHeader = "%YAML:1.0\n";

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& field, const std::string& what) {
  throw std::runtime_error(file.string() + ": " + field + ": " + what);
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

cv::FileStorage open_yaml(const std::filesystem::path& file, bool add_header_if_missing) {
  std::string text = read_text(file);
  if (add_header_if_missing && text.rfind("%YAML", 0) != 0) text = kOpenCvYamlHeader + text;
  try {
    cv::FileStorage storage(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    if (!storage.isOpened()) throw std::runtime_error(file.string() + ": not a readable YAML file");
    return storage;
  } catch (const cv::Exception& e) {
    throw std::runtime_error(file.string() + ": not valid YAML (" + e.err + ")");
  }
}

// "nan", "inf" or "-inf" (std::to_string prints a nan's sign bit, "-nan").
std::string non_finite_text(double value) { return std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf"; }

double read_number(const cv::FileNode& node, const std::filesystem::path& file, const std::string& field) {
  if (node.empty() || node.isNone()) fail(file, field, "missing (expected a number)");
  if (!node.isReal() && !node.isInt()) fail(file, field, "expected a number");
  const double value = static_cast<double>(node);
  if (!std::isfinite(value)) fail(file, field, "expected a finite number, got " + non_finite_text(value));
  return value;
}

// An image width or height: a whole number of pixels in 1..kMaxImageSidePx (checked before the
// conversion to int, which would be undefined for a huge value).
int read_image_side(double value, const std::filesystem::path& file, const std::string& field) {
  if (!(value >= 1.0 && value <= static_cast<double>(kMaxImageSidePx)) ||
      value != static_cast<double>(static_cast<int>(value))) {
    std::ostringstream text;
    text << "image size " << value << " px: " << image_size_expectation();
    fail(file, field, text.str());
  }
  return static_cast<int>(value);
}

double read_positive(const cv::FileNode& node, const std::filesystem::path& file, const std::string& field) {
  const double value = read_number(node, file, field);
  if (!(value > 0.0)) fail(file, field, "expected a positive number, got " + std::to_string(value));
  return value;
}

// A YAML sequence of numbers whose length is one of `allowed_sizes`.
std::vector<double> read_sequence(const cv::FileNode& node, const std::filesystem::path& file, const std::string& field,
                                  std::initializer_list<std::size_t> allowed_sizes) {
  std::string expected;
  for (std::size_t n : allowed_sizes) expected += (expected.empty() ? "" : " or ") + std::to_string(n);
  if (node.empty() || node.isNone()) fail(file, field, "missing (expected a list of " + expected + " numbers)");
  if (!node.isSeq()) fail(file, field, "expected a list of " + expected + " numbers");
  std::vector<double> values;
  for (const cv::FileNode& item : node) {
    if (!item.isReal() && !item.isInt()) fail(file, field, "expected only numbers in the list");
    const double value = static_cast<double>(item);
    if (!std::isfinite(value)) {
      fail(file, field,
           "expected finite numbers, item " + std::to_string(values.size()) + " is " + non_finite_text(value));
    }
    values.push_back(value);
  }
  bool size_ok = false;
  for (std::size_t n : allowed_sizes) size_ok = size_ok || values.size() == n;
  if (!size_ok) fail(file, field, "expected " + expected + " numbers, got " + std::to_string(values.size()));
  return values;
}

// An OpenCV "!!opencv-matrix" of the given size, as doubles.
cv::Mat read_matrix(const cv::FileNode& node, const std::filesystem::path& file, const std::string& field, int rows,
                    int cols) {
  if (node.empty() || node.isNone())
    fail(file, field, "missing (expected a " + std::to_string(rows) + "x" + std::to_string(cols) + " !!opencv-matrix)");
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    fail(file, field, "expected an !!opencv-matrix");
  }
  if (m.empty() || m.total() != static_cast<std::size_t>(rows * cols)) {
    fail(file, field, "expected a " + std::to_string(rows) + "x" + std::to_string(cols) + " matrix");
  }
  cv::Mat out;
  m.reshape(1, rows).convertTo(out, CV_64F);
  if (!cv::checkRange(out)) fail(file, field, "expected finite numbers (the matrix holds a nan or inf)");
  return out;
}

void check_rotation(const Eigen::Matrix3d& R, const std::filesystem::path& file, const std::string& field) {
  constexpr double kRotationTolerance = 1e-3;  // calibration files print ~9 digits; 1e-3 catches typos only
  if ((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > kRotationTolerance || R.determinant() < 0.0) {
    fail(file, field, "expected a rotation matrix (orthonormal, determinant +1)");
  }
}

CameraModel read_euroc_camera(const std::filesystem::path& file, double* rate_hz) {
  cv::FileStorage fs = open_yaml(file, /*add_header_if_missing=*/true);
  CameraModel camera;

  const std::string model = static_cast<std::string>(fs["camera_model"]);
  if (model != "pinhole") fail(file, "camera_model", "expected 'pinhole', got '" + model + "'");

  const std::vector<double> intrinsics = read_sequence(fs["intrinsics"], file, "intrinsics", {4});
  camera.fx_px = intrinsics[0];
  camera.fy_px = intrinsics[1];
  camera.cx_px = intrinsics[2];
  camera.cy_px = intrinsics[3];
  if (!(camera.fx_px > 0.0 && camera.fy_px > 0.0)) fail(file, "intrinsics", "expected positive fu, fv");

  const std::vector<double> resolution = read_sequence(fs["resolution"], file, "resolution", {2});
  camera.width_px = read_image_side(resolution[0], file, "resolution");
  camera.height_px = read_image_side(resolution[1], file, "resolution");

  const std::string distortion = static_cast<std::string>(fs["distortion_model"]);
  if (distortion == "radial-tangential" || distortion == "radtan") {
    camera.distortion_model = DistortionModel::kRadialTangential;
    camera.distortion = read_sequence(fs["distortion_coefficients"], file, "distortion_coefficients", {4, 5});
  } else if (distortion == "equidistant") {
    camera.distortion_model = DistortionModel::kEquidistant;
    camera.distortion = read_sequence(fs["distortion_coefficients"], file, "distortion_coefficients", {4});
  } else if (distortion == "none" || distortion.empty()) {
    camera.distortion_model = DistortionModel::kNone;
  } else {
    fail(file, "distortion_model",
         "expected 'radial-tangential', 'equidistant' or 'none', got '" + distortion.substr(0, 40) + "'");
  }

  const cv::FileNode t_bs = fs["T_BS"];
  if (t_bs.empty() || t_bs.isNone()) fail(file, "T_BS", "missing (expected {rows: 4, cols: 4, data: [16 numbers]})");
  const std::vector<double> data = read_sequence(t_bs["data"], file, "T_BS.data", {16});
  Eigen::Matrix4d T = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(data.data());
  check_rotation(T.topLeftCorner<3, 3>(), file, "T_BS");
  camera.T_BS.matrix() = T;
  camera.T_BS.makeAffine();

  if (!fs["rate_hz"].empty()) *rate_hz = read_positive(fs["rate_hz"], file, "rate_hz");
  return camera;
}

}  // namespace

const char* to_string(DistortionModel model) {
  switch (model) {
    case DistortionModel::kNone: return "none";
    case DistortionModel::kRadialTangential: return "radial-tangential";
    case DistortionModel::kEquidistant: return "equidistant";
  }
  return "?";
}

StereoCalibration load_euroc_calibration(const std::filesystem::path& mav0_dir) {
  const std::filesystem::path left_file = mav0_dir / "cam0" / "sensor.yaml";
  const std::filesystem::path right_file = mav0_dir / "cam1" / "sensor.yaml";
  StereoCalibration calibration;
  double left_rate_hz = 0.0;
  double right_rate_hz = 0.0;
  calibration.left = read_euroc_camera(left_file, &left_rate_hz);
  calibration.right = read_euroc_camera(right_file, &right_rate_hz);
  if (calibration.left.width_px != calibration.right.width_px ||
      calibration.left.height_px != calibration.right.height_px) {
    fail(right_file, "resolution", "expected the same resolution as " + left_file.string());
  }
  calibration.rate_hz = left_rate_hz;
  calibration.source = left_file.string() + ", " + right_file.string();
  return calibration;
}

StereoCalibration load_kitti_calibration(const std::filesystem::path& calib_txt, int width_px, int height_px) {
  if (!image_size_plausible(static_cast<std::uint64_t>(std::max(width_px, 0)),
                            static_cast<std::uint64_t>(std::max(height_px, 0)))) {
    fail(calib_txt, "image size",
         std::to_string(width_px) + "x" + std::to_string(height_px) + ": " + image_size_expectation());
  }
  std::ifstream in(calib_txt);
  if (!in) throw std::runtime_error(calib_txt.string() + ": cannot open file");
  std::optional<std::vector<double>> p0;
  std::optional<std::vector<double>> p1;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key != "P0:" && key != "P1:") continue;
    std::vector<double> values;
    double v = 0.0;
    while (fields >> v) values.push_back(v);
    if (!fields.eof() || values.size() != 12) {
      fail(calib_txt, key.substr(0, 2), "expected 12 numbers (a 3x4 projection matrix)");
    }
    (key == "P0:" ? p0 : p1) = values;
  }
  if (!p0) fail(calib_txt, "P0", "missing (expected a line 'P0: 12 numbers')");
  if (!p1) fail(calib_txt, "P1", "missing (expected a line 'P1: 12 numbers')");

  StereoCalibration calibration;
  calibration.input_rectified = true;
  CameraModel& left = calibration.left;
  left.width_px = width_px;
  left.height_px = height_px;
  left.fx_px = (*p0)[0];
  left.cx_px = (*p0)[2];
  left.fy_px = (*p0)[5];
  left.cy_px = (*p0)[6];
  if (!(left.fx_px > 0.0 && left.fy_px > 0.0)) fail(calib_txt, "P0", "expected positive focal lengths");
  if ((*p1)[0] != left.fx_px || (*p1)[2] != left.cx_px || (*p1)[5] != left.fy_px || (*p1)[6] != left.cy_px) {
    fail(calib_txt, "P1", "expected the same intrinsics as P0 (rectified pair)");
  }
  // P1 = K [I | -b e_x] relative to the left camera: P1[3] - P0[3] = -fx * baseline.
  const double baseline_m = -((*p1)[3] - (*p0)[3]) / left.fx_px;
  if (!(baseline_m > 0.0)) fail(calib_txt, "P1", "expected P1[0][3] < 0 (right camera to the right of the left)");
  calibration.right = left;
  calibration.right.T_BS = Pose3::Identity();
  calibration.right.T_BS.translation() = Eigen::Vector3d(baseline_m, 0.0, 0.0);
  calibration.source = calib_txt.string();
  return calibration;
}

namespace {

// ORB-SLAM3's settings format (File.version "1.0"): Camera1.* / Camera2.* with Stereo.T_c1_c2 for a raw
// pair, Camera1.* with Stereo.b for a rectified one; IMU.T_b_c1 (when given) places the rig on the body.
StereoCalibration load_orbslam3_settings(const cv::FileStorage& fs, const std::filesystem::path& file) {
  const std::string type = fs["Camera.type"].isString() ? static_cast<std::string>(fs["Camera.type"]) : "";
  if (type != "PinHole" && type != "KannalaBrandt8") {
    fail(file, "Camera.type",
         "expected \"PinHole\" or \"KannalaBrandt8\" (heslam rectifies pinhole radial-tangential and equidistant "
         "fisheye cameras; got '" +
             type.substr(0, 40) + "')");
  }
  const bool fisheye = type == "KannalaBrandt8";
  for (const char* key : {"Camera.newWidth", "Camera.newHeight"}) {
    if (!fs[key].empty()) fail(file, key, "not supported: give the calibration of the images as they are published");
  }
  StereoCalibration calibration;
  calibration.source = file.string();
  if (!fs["Camera.fps"].empty()) calibration.rate_hz = read_positive(fs["Camera.fps"], file, "Camera.fps");
  const int width_px = read_image_side(read_number(fs["Camera.width"], file, "Camera.width"), file, "Camera.width");
  const int height_px = read_image_side(read_number(fs["Camera.height"], file, "Camera.height"), file, "Camera.height");

  const auto read_camera = [&](const std::string& name) {
    CameraModel camera;
    camera.width_px = width_px;
    camera.height_px = height_px;
    camera.fx_px = read_positive(fs[name + ".fx"], file, name + ".fx");
    camera.fy_px = read_positive(fs[name + ".fy"], file, name + ".fy");
    camera.cx_px = read_number(fs[name + ".cx"], file, name + ".cx");
    camera.cy_px = read_number(fs[name + ".cy"], file, name + ".cy");
    if (fisheye) {
      // Kannala-Brandt: k1 k2 k3 k4, all four required (ORB-SLAM3 reads all four).
      for (const char* k : {".k1", ".k2", ".k3", ".k4"}) {
        camera.distortion.push_back(read_number(fs[name + k], file, name + k));
      }
      for (const char* k : {".p1", ".p2"}) {
        if (!fs[name + k].empty()) fail(file, name + k, "not a KannalaBrandt8 coefficient (k1 k2 k3 k4)");
      }
      camera.distortion_model = DistortionModel::kEquidistant;
      return camera;
    }
    // Radial-tangential k1 k2 p1 p2 [k3] when any of them is given (then the first four are required).
    const std::array<std::string, 4> required{name + ".k1", name + ".k2", name + ".p1", name + ".p2"};
    if (std::none_of(required.begin(), required.end(), [&](const std::string& key) { return !fs[key].empty(); })) {
      return camera;
    }
    for (const std::string& key : required) camera.distortion.push_back(read_number(fs[key], file, key));
    if (!fs[name + ".k3"].empty()) camera.distortion.push_back(read_number(fs[name + ".k3"], file, name + ".k3"));
    camera.distortion_model = DistortionModel::kRadialTangential;
    return camera;
  };
  const auto read_pose = [&](const char* key) {
    const cv::Mat m = read_matrix(fs[key], file, key, 4, 4);
    Eigen::Matrix4d T;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) T(r, c) = m.at<double>(r, c);
    }
    check_rotation(T.topLeftCorner<3, 3>(), file, key);
    Pose3 pose = Pose3::Identity();
    pose.matrix() = T;
    pose.makeAffine();
    return pose;
  };
  const Pose3 T_b_c1 = fs["IMU.T_b_c1"].empty() ? Pose3::Identity() : read_pose("IMU.T_b_c1");

  calibration.left = read_camera("Camera1");
  calibration.left.T_BS = T_b_c1;
  if (fs["Camera2.fx"].empty()) {
    if (fisheye) fail(file, "Camera2.fx", "missing: a KannalaBrandt8 pair is raw (give Camera2.* and Stereo.T_c1_c2)");
    // Rectified pair (ORB-SLAM3's KITTI files): Camera1 is the rectified model, Stereo.b the baseline.
    if (calibration.left.distortion_model != DistortionModel::kNone &&
        std::any_of(calibration.left.distortion.begin(), calibration.left.distortion.end(),
                    [](double k) { return k != 0.0; })) {
      fail(file, "Camera1.k1",
           "expected no distortion for a rectified pair (give Camera2.* and Stereo.T_c1_c2 for raw images)");
    }
    calibration.left.distortion.clear();
    calibration.left.distortion_model = DistortionModel::kNone;
    calibration.input_rectified = true;
    const double baseline_m = read_positive(fs["Stereo.b"], file, "Stereo.b");
    calibration.right = calibration.left;
    Pose3 T_c1_c2 = Pose3::Identity();
    T_c1_c2.translation() = Eigen::Vector3d(baseline_m, 0.0, 0.0);
    calibration.right.T_BS = T_b_c1 * T_c1_c2;
    return calibration;
  }
  calibration.right = read_camera("Camera2");
  const Pose3 T_c1_c2 = read_pose("Stereo.T_c1_c2");  // camera 2 -> camera 1
  if (!(T_c1_c2.translation().x() > 0.0)) {
    fail(file, "Stereo.T_c1_c2", "expected camera 2 to the right of camera 1 (a positive x translation)");
  }
  calibration.right.T_BS = T_b_c1 * T_c1_c2;
  return calibration;
}

}  // namespace

StereoCalibration load_orbslam_settings(const std::filesystem::path& settings_yaml) {
  const std::filesystem::path& file = settings_yaml;
  cv::FileStorage fs = open_yaml(file, /*add_header_if_missing=*/true);
  if (!fs["File.version"].empty()) {
    const std::string version = fs["File.version"].isString() ? static_cast<std::string>(fs["File.version"]) : "";
    if (version != "1.0")
      fail(file, "File.version", "expected \"1.0\" (ORB-SLAM3's format) or no such key (ORB-SLAM2's)");
    return load_orbslam3_settings(fs, file);
  }
  StereoCalibration calibration;
  calibration.source = file.string();
  if (!fs["Camera.fps"].empty()) calibration.rate_hz = read_positive(fs["Camera.fps"], file, "Camera.fps");

  const double fx = read_positive(fs["Camera.fx"], file, "Camera.fx");
  const double fy = read_positive(fs["Camera.fy"], file, "Camera.fy");
  const double cx = read_number(fs["Camera.cx"], file, "Camera.cx");
  const double cy = read_number(fs["Camera.cy"], file, "Camera.cy");
  const double bf = read_positive(fs["Camera.bf"], file, "Camera.bf");
  const int width_px = read_image_side(read_number(fs["Camera.width"], file, "Camera.width"), file, "Camera.width");
  const int height_px = read_image_side(read_number(fs["Camera.height"], file, "Camera.height"), file, "Camera.height");

  if (fs["LEFT.K"].empty()) {
    // Already rectified input (KITTI style): Camera.* is the rectified model, no distortion allowed.
    for (const char* key : {"Camera.k1", "Camera.k2", "Camera.p1", "Camera.p2", "Camera.k3"}) {
      if (!fs[key].empty() && read_number(fs[key], file, key) != 0.0) {
        fail(file, key, "expected 0 for rectified stereo input (give LEFT.K/D/R/P, RIGHT.K/D/R/P for raw images)");
      }
    }
    calibration.input_rectified = true;
    CameraModel& left = calibration.left;
    left.width_px = width_px;
    left.height_px = height_px;
    left.fx_px = fx;
    left.fy_px = fy;
    left.cx_px = cx;
    left.cy_px = cy;
    calibration.right = left;
    calibration.right.T_BS.translation() = Eigen::Vector3d(bf / fx, 0.0, 0.0);
    return calibration;
  }

  ExplicitRectification rect;
  auto read_camera = [&](const std::string& side, Eigen::Matrix3d* R, Eigen::Matrix<double, 3, 4>* P) {
    CameraModel camera;
    const cv::Mat K = read_matrix(fs[side + ".K"], file, side + ".K", 3, 3);
    camera.fx_px = K.at<double>(0, 0);
    camera.fy_px = K.at<double>(1, 1);
    camera.cx_px = K.at<double>(0, 2);
    camera.cy_px = K.at<double>(1, 2);
    if (!(camera.fx_px > 0.0 && camera.fy_px > 0.0)) fail(file, side + ".K", "expected positive focal lengths");
    const cv::FileNode d_node = fs[side + ".D"];
    if (d_node.empty()) fail(file, side + ".D", "missing (expected a 1x4 or 1x5 !!opencv-matrix k1 k2 p1 p2 [k3])");
    cv::Mat D;
    d_node >> D;
    if (D.total() != 4 && D.total() != 5) fail(file, side + ".D", "expected 4 or 5 coefficients k1 k2 p1 p2 [k3]");
    D = D.reshape(1, 1);
    D.convertTo(D, CV_64F);
    camera.distortion.assign(D.begin<double>(), D.end<double>());
    camera.distortion_model = DistortionModel::kRadialTangential;
    const cv::Mat Rm = read_matrix(fs[side + ".R"], file, side + ".R", 3, 3);
    const cv::Mat Pm = read_matrix(fs[side + ".P"], file, side + ".P", 3, 4);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) (*R)(r, c) = Rm.at<double>(r, c);
      for (int c = 0; c < 4; ++c) (*P)(r, c) = Pm.at<double>(r, c);
    }
    check_rotation(*R, file, side + ".R");
    camera.width_px = fs[side + ".width"].empty()
                          ? width_px
                          : static_cast<int>(read_positive(fs[side + ".width"], file, side + ".width"));
    camera.height_px = fs[side + ".height"].empty()
                           ? height_px
                           : static_cast<int>(read_positive(fs[side + ".height"], file, side + ".height"));
    return camera;
  };
  calibration.left = read_camera("LEFT", &rect.R_left, &rect.P_left);
  calibration.right = read_camera("RIGHT", &rect.R_right, &rect.P_right);

  if (!(rect.P_left(0, 0) > 0.0)) fail(file, "LEFT.P", "expected a positive focal length P[0][0]");
  const double baseline_m = -rect.P_right(0, 3) / rect.P_right(0, 0);
  if (!(baseline_m > 0.0)) fail(file, "RIGHT.P", "expected P[0][3] = -fx * baseline < 0");
  constexpr double kBfTolerance = 1e-3;  // Camera.bf and RIGHT.P are printed from the same number
  if (std::abs(baseline_m * rect.P_left(0, 0) - bf) > kBfTolerance * bf) {
    fail(file, "Camera.bf", "expected -RIGHT.P[0][3] = " + std::to_string(-rect.P_right(0, 3)));
  }
  calibration.set_explicit_rectification(rect, baseline_m);
  return calibration;
}

void StereoCalibration::set_explicit_rectification(const ExplicitRectification& rect, double baseline_m) {
  Pose3 T_rl = Pose3::Identity();
  T_rl.linear() = rect.R_right.transpose() * rect.R_left;
  T_rl.translation() = -rect.R_right.transpose() * Eigen::Vector3d(baseline_m, 0.0, 0.0);
  right.T_BS = T_rl.inverse();
  explicit_rectification = rect;
}

}  // namespace heslam
