// ROS 2 camera topics -> heslam camera input (see ros2_input_conversions.hpp).
#include "tools/ros2_bridge/ros2_input_conversions.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <opencv2/core.hpp>

#include "tools/camera/camera_calibration.hpp"
#include "tools/dataset/imu_reader.hpp"

namespace heslam::ros2 {
namespace {

constexpr double kRotationTolerance = 1e-6;  // R R^T = I to this, entry by entry (CameraInfo prints 1e-9)

[[noreturn]] void fail(const std::string& topic, const std::string& field, const std::string& what) {
  throw std::runtime_error("topic '" + topic + "': field " + field + ": " + what);
}

Eigen::Matrix3d matrix3(const double (&m)[9]) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = m[3 * r + c];
  }
  return out;
}

Eigen::Matrix<double, 3, 4> matrix34(const double (&m)[12]) {
  Eigen::Matrix<double, 3, 4> out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) out(r, c) = m[4 * r + c];
  }
  return out;
}

// K, D and size of one raw camera; R and P into `R` / `P`.
CameraModel raw_camera(const CameraInfoSource& source, Eigen::Matrix3d& R, Eigen::Matrix<double, 3, 4>& P) {
  const CameraInfo& info = source.info;
  if (info.width == 0 || info.height == 0) fail(source.topic, "width/height", "expected the image size, got 0");
  if (info.binning_x > 1 || info.binning_y > 1) fail(source.topic, "binning_x/binning_y", "binning is not supported");
  CameraModel camera;
  camera.width_px = static_cast<int>(info.width);
  camera.height_px = static_cast<int>(info.height);
  const Eigen::Matrix3d K = matrix3(info.k);
  camera.fx_px = K(0, 0);
  camera.fy_px = K(1, 1);
  camera.cx_px = K(0, 2);
  camera.cy_px = K(1, 2);
  if (!(camera.fx_px > 0.0 && camera.fy_px > 0.0)) fail(source.topic, "k", "expected positive focal lengths");
  const std::string model = info.distortion_model != nullptr ? info.distortion_model : "";
  std::vector<double> d(info.d._buffer, info.d._buffer + info.d._length);
  if (model == "rational_polynomial") {
    // k1 k2 p1 p2 k3 k4 k5 k6: with k4..k6 zero it is plumb_bob exactly.
    if (d.size() < 5 || d.size() > 8) fail(source.topic, "d", "expected 5 to 8 rational_polynomial coefficients");
    for (std::size_t i = 5; i < d.size(); ++i) {
      if (d[i] != 0.0) {
        fail(source.topic, "d", "rational_polynomial k4..k6 must be 0: heslam models plumb_bob (k1 k2 p1 p2 k3) only");
      }
    }
    d.resize(5);
  } else if (model == "equidistant") {
    // image_geometry's fisheye (Kannala-Brandt) model, as camera_calibration --fisheye writes it
    if (d.size() != 4) fail(source.topic, "d", "expected 4 equidistant coefficients k1 k2 k3 k4");
  } else if (model != "plumb_bob") {
    fail(source.topic, "distortion_model",
         "'" + model + "': expected plumb_bob, rational_polynomial (with k4..k6 = 0) or equidistant");
  } else if (d.size() != 4 && d.size() != 5) {
    fail(source.topic, "d", "expected 4 or 5 plumb_bob coefficients k1 k2 p1 p2 [k3]");
  }
  camera.distortion = d;
  camera.distortion_model = model == "equidistant" ? DistortionModel::kEquidistant : DistortionModel::kRadialTangential;
  R = matrix3(info.r);
  if (!((R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < kRotationTolerance) ||
      !(R.determinant() > 0.0)) {
    fail(source.topic, "r", "expected a rotation (the rectifying rotation; identity for a monocular camera)");
  }
  P = matrix34(info.p);
  if (!(P(0, 0) > 0.0 && P(1, 1) > 0.0)) fail(source.topic, "p", "expected positive focal lengths P[0][0], P[1][1]");
  return camera;
}

}  // namespace

std::int64_t to_stamp_ns(const Time& time) { return std::int64_t{time.sec} * 1'000'000'000 + time.nanosec; }

StereoCalibration to_stereo_calibration(const CameraInfoSource& left, const CameraInfoSource& right,
                                        bool images_rectified) {
  ExplicitRectification rect;
  StereoCalibration calibration;
  calibration.left = raw_camera(left, rect.R_left, rect.P_left);
  calibration.right = raw_camera(right, rect.R_right, rect.P_right);
  calibration.source = "ROS 2 CameraInfo on " + left.topic + " and " + right.topic;
  if (calibration.left.width_px != calibration.right.width_px ||
      calibration.left.height_px != calibration.right.height_px) {
    fail(right.topic, "width/height", "expected the left camera's size");
  }
  const double baseline_m = -rect.P_right(0, 3) / rect.P_right(0, 0);
  if (!(baseline_m > 0.0)) fail(right.topic, "p", "expected P[0][3] = -fx * baseline < 0 (the right camera)");
  if ((rect.P_left.leftCols<3>() - rect.P_right.leftCols<3>()).cwiseAbs().maxCoeff() > 1e-6 * rect.P_left(0, 0)) {
    fail(right.topic, "p", "expected the left camera's rectified intrinsics (P[0..2][0..2] of both equal)");
  }
  if (images_rectified) {
    // The images are the rectified ones: P is their pinhole, no distortion, the right at +baseline.
    calibration.input_rectified = true;
    CameraModel rectified;
    rectified.width_px = calibration.left.width_px;
    rectified.height_px = calibration.left.height_px;
    rectified.fx_px = rect.P_left(0, 0);
    rectified.fy_px = rect.P_left(1, 1);
    rectified.cx_px = rect.P_left(0, 2);
    rectified.cy_px = rect.P_left(1, 2);
    calibration.left = rectified;
    calibration.right = rectified;
    calibration.right.T_BS.translation() = Eigen::Vector3d(baseline_m, 0.0, 0.0);
    return calibration;
  }
  // As load_orbslam_settings with LEFT/RIGHT.K/D/R/P; the body is the left camera.
  calibration.set_explicit_rectification(rect, baseline_m);
  return calibration;
}

PackedImage to_packed_image(const Image& image, const std::string& topic, std::uint32_t expected_width_px,
                            std::uint32_t expected_height_px) {
  const std::string encoding = image.encoding != nullptr ? image.encoding : "";
  PackedImage out;
  std::uint32_t channels = 0;
  if (encoding == "mono8") {
    channels = 1;
    out.encoding = heslam_msg_ENCODING_MONO8;
  } else if (encoding == "bgr8" || encoding == "rgb8") {
    channels = 3;
    out.encoding = heslam_msg_ENCODING_BGR8;
  } else {
    fail(topic, "encoding", "'" + encoding + "': expected mono8, bgr8 or rgb8");
  }
  if (image.width == 0 || image.height == 0) fail(topic, "width/height", "empty image");
  if ((expected_width_px != 0 && image.width != expected_width_px) ||
      (expected_height_px != 0 && image.height != expected_height_px)) {
    fail(topic, "width/height",
         std::to_string(image.width) + "x" + std::to_string(image.height) + " differs from the CameraInfo's " +
             std::to_string(expected_width_px) + "x" + std::to_string(expected_height_px));
  }
  const std::uint64_t row_bytes = std::uint64_t{image.width} * channels;
  if (image.step < row_bytes) {
    fail(topic, "step", std::to_string(image.step) + " is less than width x channels = " + std::to_string(row_bytes));
  }
  if (image.data._length != std::uint64_t{image.step} * image.height) {
    fail(topic, "data",
         std::to_string(image.data._length) +
             " bytes, expected step x height = " + std::to_string(std::uint64_t{image.step} * image.height));
  }
  out.width_px = image.width;
  out.height_px = image.height;
  out.pixels.resize(row_bytes * image.height);
  for (std::uint32_t row = 0; row < image.height; ++row) {
    const std::uint8_t* from = image.data._buffer + std::uint64_t{row} * image.step;
    std::uint8_t* to = out.pixels.data() + row * row_bytes;
    std::memcpy(to, from, row_bytes);
    if (encoding == "rgb8") {
      for (std::uint64_t i = 0; i < row_bytes; i += 3) std::swap(to[i], to[i + 2]);
    }
  }
  return out;
}

namespace {

// The frames missing in an interval between two images, for a camera of this period.
std::uint64_t frames_missing_in(std::int64_t interval_ns, std::int64_t period_ns) {
  if (static_cast<double>(interval_ns) <= FrameGapCounter::kGapFactor * static_cast<double>(period_ns)) return 0;
  const long long periods = std::llround(static_cast<double>(interval_ns) / static_cast<double>(period_ns));
  return static_cast<std::uint64_t>(std::max(periods - 1, 1LL));
}

}  // namespace

std::int64_t FrameGapCounter::period_ns() const {
  if (!judging_ || intervals_.empty()) return 0;
  std::vector<std::int64_t> sorted = intervals_;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  return *middle;
}

std::uint64_t FrameGapCounter::judge(std::int64_t interval_ns) {
  const std::uint64_t missing = frames_missing_in(interval_ns, period_ns());
  if (missing == 0) {
    intervals_.push_back(interval_ns);
    if (intervals_.size() > kIntervals) intervals_.erase(intervals_.begin());
  }
  return missing;
}

std::uint64_t FrameGapCounter::add(std::int64_t stamp_ns) {
  if (newest_ns_ && stamp_ns <= *newest_ns_) return 0;
  const std::optional<std::int64_t> previous = newest_ns_;
  newest_ns_ = stamp_ns;
  if (!previous) return 0;
  const std::int64_t interval = stamp_ns - *previous;
  std::uint64_t found = 0;
  if (judging_) {
    found = judge(interval);
  } else {
    intervals_.push_back(interval);
    if (intervals_.size() == kJudgeAfter) {
      // The first intervals judged against their own median (one gap among them does not move it).
      judging_ = true;
      const std::int64_t period = period_ns();
      std::vector<std::int64_t> ordinary;
      for (const std::int64_t first : intervals_) {
        const std::uint64_t missing = frames_missing_in(first, period);
        found += missing;
        if (missing == 0) ordinary.push_back(first);
      }
      intervals_ = std::move(ordinary);
    }
  }
  missing_ += found;
  return found;
}

std::optional<StereoPairer::Pair> StereoPairer::add(Side side, std::int64_t stamp_ns, PackedImage image) {
  if (last_pair_stamp_ns_ && stamp_ns <= *last_pair_stamp_ns_) {
    throw std::runtime_error("stamp " + std::to_string(stamp_ns) + " ns is not after the last pair's " +
                             std::to_string(*last_pair_stamp_ns_) + " ns (stamps going backwards, or too late)");
  }
  std::map<std::int64_t, PackedImage>& mine = pending_[static_cast<int>(side)];
  std::map<std::int64_t, PackedImage>& other = pending_[1 - static_cast<int>(side)];
  const auto partner = other.find(stamp_ns);
  if (partner == other.end()) {
    if (!mine.emplace(stamp_ns, std::move(image)).second) {
      throw std::runtime_error("stamp " + std::to_string(stamp_ns) + " ns: a second image of the same side");
    }
    if (mine.size() > kMaxPending) {
      mine.erase(mine.begin());
      ++unpaired_;
    }
    return std::nullopt;
  }
  Pair pair;
  pair.stamp_ns = stamp_ns;
  PackedImage& partner_image = partner->second;
  pair.left = side == Side::kLeft ? std::move(image) : std::move(partner_image);
  pair.right = side == Side::kLeft ? std::move(partner_image) : std::move(image);
  for (std::map<std::int64_t, PackedImage>& queue : pending_) {
    const auto end = queue.upper_bound(stamp_ns);
    for (auto it = queue.begin(); it != end; ++it) unpaired_ += it->first == stamp_ns ? 0 : 1;
    queue.erase(queue.begin(), end);
  }
  last_pair_stamp_ns_ = stamp_ns;
  return pair;
}

namespace {

void check_vector(const geometry_msgs_msg_dds__Vector3_& v, const std::string& topic, const char* field) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
    throw std::runtime_error("topic '" + topic + "': field " + field + ": not a finite number (" + std::to_string(v.x) +
                             ", " + std::to_string(v.y) + ", " + std::to_string(v.z) + "): reading dropped");
  }
}

// A YAML file of either dialect (EuRoC's %YAML:1.0 with OpenCV maps, Kalibr's plain PyYAML output).
cv::FileStorage open_yaml(const std::filesystem::path& file, const char* expected) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open (expected " + expected + ")");
  std::stringstream text;
  text << in.rdbuf();
  cv::FileStorage storage;
  try {
    storage.open(kalibr_yaml_for_opencv(text.str()),
                 cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& error) {
    throw std::runtime_error(file.string() + ": not a YAML file cv::FileStorage can read (" + error.err + ")");
  }
  if (!storage.isOpened()) throw std::runtime_error(file.string() + ": not a YAML file cv::FileStorage can read");
  return storage;
}

Pose3 rigid(const Eigen::Matrix4d& matrix, const std::string& where) {
  const Eigen::Matrix3d R = matrix.topLeftCorner<3, 3>();
  const bool finite = matrix.allFinite();
  if (!finite || (R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6 || R.determinant() < 0.0 ||
      (matrix.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9) {
    throw std::runtime_error(where + ": expected a rigid transform (a rotation and a translation)");
  }
  Pose3 pose = Pose3::Identity();
  pose.linear() = R;
  pose.translation() = matrix.topRightCorner<3, 1>();
  return pose;
}

// EuRoC: {rows: 4, cols: 4, data: [16 numbers]}.
Pose3 euroc_matrix(const cv::FileNode& node, const std::string& where) {
  const cv::FileNode data = node["data"];
  if (!data.isSeq() || data.size() != 16)
    throw std::runtime_error(where + ": expected {rows: 4, cols: 4, data: [16 numbers]}");
  Eigen::Matrix4d matrix;
  int i = 0;
  for (const cv::FileNode& item : data) {
    if (!item.isReal() && !item.isInt()) throw std::runtime_error(where + ".data: expected 16 numbers");
    matrix(i / 4, i % 4) = item.real();
    ++i;
  }
  return rigid(matrix, where);
}

// Kalibr: 4 rows of 4 numbers.
Pose3 kalibr_matrix(const cv::FileNode& node, const std::string& where) {
  if (!node.isSeq() || node.size() != 4) throw std::runtime_error(where + ": expected 4 rows of 4 numbers");
  Eigen::Matrix4d matrix;
  int r = 0;
  for (const cv::FileNode& row : node) {
    if (!row.isSeq() || row.size() != 4) throw std::runtime_error(where + ": expected 4 rows of 4 numbers");
    int c = 0;
    for (const cv::FileNode& item : row) {
      if (!item.isReal() && !item.isInt()) throw std::runtime_error(where + ": expected 4 rows of 4 numbers");
      matrix(r, c++) = item.real();
    }
    ++r;
  }
  return rigid(matrix, where);
}

}  // namespace

void check_same_encoding(const StereoPairer::Pair& pair, const std::string& left_topic,
                         const std::string& right_topic) {
  if (pair.left.encoding == pair.right.encoding) return;
  const auto name = [](heslam_msg_ImageEncoding encoding) {
    return encoding == heslam_msg_ENCODING_MONO8 ? "mono8" : "bgr8";
  };
  throw std::runtime_error("topics '" + left_topic + "' and '" + right_topic + "': field encoding: the pair at stamp " +
                           std::to_string(pair.stamp_ns) + " ns mixes " + name(pair.left.encoding) + " (left) and " +
                           name(pair.right.encoding) + " (right): pair dropped");
}

ImuSample to_imu_sample(const Imu& imu, const std::string& topic) {
  if (imu.linear_acceleration_covariance[0] == -1.0) {
    throw UnusableImu("topic '" + topic +
                      "': field linear_acceleration_covariance[0] is -1: the IMU gives no linear acceleration "
                      "(an orientation-only IMU); heslam's inertial tracking needs angular velocity and linear "
                      "acceleration");
  }
  if (imu.angular_velocity_covariance[0] == -1.0) {
    throw UnusableImu("topic '" + topic +
                      "': field angular_velocity_covariance[0] is -1: the IMU gives no angular velocity; heslam's "
                      "inertial tracking needs angular velocity and linear acceleration");
  }
  if (imu.header.stamp.sec < 0) {
    throw std::runtime_error("topic '" + topic + "': field header.stamp: negative (" +
                             std::to_string(imu.header.stamp.sec) + " s): reading dropped");
  }
  check_vector(imu.angular_velocity, topic, "angular_velocity");
  check_vector(imu.linear_acceleration, topic, "linear_acceleration");
  ImuSample sample;
  sample.stamp_ns = to_stamp_ns(imu.header.stamp);
  sample.gyro_rad_s = Eigen::Vector3d(imu.angular_velocity.x, imu.angular_velocity.y, imu.angular_velocity.z);
  sample.accel_m_s2 = Eigen::Vector3d(imu.linear_acceleration.x, imu.linear_acceleration.y, imu.linear_acceleration.z);
  return sample;
}

ImuCalibration load_ros2_imu_calibration(const std::filesystem::path& imu_file,
                                         const std::filesystem::path& extrinsic_file) {
  ImuCalibration calibration;
  const cv::FileStorage imu = open_yaml(imu_file, "an IMU sensor.yaml (EuRoC) or imu.yaml (Kalibr)");
  // The replay's reader of the noise model (tools/dataset/imu_reader.hpp): the same figures, the same errors.
  calibration.noise = read_imu_noise_model(imu.root(), imu_file);
  if (!imu["rate_hz"].empty()) {
    calibration.rate_hz = read_positive_number(imu["rate_hz"], imu_file, "rate_hz");
  } else if (!imu["update_rate"].empty()) {
    calibration.rate_hz = read_positive_number(imu["update_rate"], imu_file, "update_rate");
  } else {
    throw std::runtime_error(imu_file.string() + ": rate_hz (EuRoC) or update_rate (Kalibr): missing");
  }
  const Pose3 T_body_imu =
      imu["T_BS"].empty() ? Pose3::Identity() : euroc_matrix(imu["T_BS"], imu_file.string() + ": T_BS");

  const cv::FileStorage extrinsic =
      open_yaml(extrinsic_file, "a Kalibr camchain (cam0.T_cam_imu) or the left camera's EuRoC sensor.yaml (T_BS)");
  if (!extrinsic["cam0"].empty()) {
    const cv::FileNode cam0 = extrinsic["cam0"];
    if (cam0["T_cam_imu"].empty()) {
      throw std::runtime_error(extrinsic_file.string() +
                               ": cam0.T_cam_imu: missing (a camchain of kalibr_calibrate_imu_camera has it)");
    }
    calibration.T_BS = kalibr_matrix(cam0["T_cam_imu"], extrinsic_file.string() + ": cam0.T_cam_imu");
    const cv::FileNode shift = cam0["timeshift_cam_imu"];
    if (!shift.empty()) {
      if ((!shift.isReal() && !shift.isInt()) || !std::isfinite(shift.real()) || std::abs(shift.real()) > 1.0) {
        throw std::runtime_error(extrinsic_file.string() + ": cam0.timeshift_cam_imu: expected seconds in [-1, 1]");
      }
      calibration.time_offset_ns = std::llround(shift.real() * 1e9);
    }
  } else if (!extrinsic["T_BS"].empty()) {
    const Pose3 T_body_cam = euroc_matrix(extrinsic["T_BS"], extrinsic_file.string() + ": T_BS");
    calibration.T_BS = T_body_cam.inverse() * T_body_imu;
  } else {
    throw std::runtime_error(extrinsic_file.string() +
                             ": neither cam0.T_cam_imu (Kalibr camchain) nor T_BS (EuRoC camera sensor.yaml)");
  }
  calibration.source = imu_file.string() + " + " + extrinsic_file.string();
  return calibration;
}

void ImuForwarder::add(const ImuSample& sample) {
  if (sample.stamp_ns <= last_stamp_ns_ || sample.stamp_ns <= watermark_ns_) {
    const bool repeated = sample.stamp_ns == last_stamp_ns_;
    throw std::runtime_error(
        "stamp " + std::to_string(sample.stamp_ns) + " ns " +
        (repeated ? std::string("repeats the last reading's")
         : sample.stamp_ns <= last_stamp_ns_
             ? "goes backwards (last reading " + std::to_string(last_stamp_ns_) + " ns)"
             : "is at or before " + std::to_string(watermark_ns_) + " ns, up to which frames already went out") +
        ": reading dropped");
  }
  last_stamp_ns_ = sample.stamp_ns;
  pending_.push_back(sample);
}

std::optional<ImuForwarder::Batch> ImuForwarder::take_batch() {
  if (pending_.empty()) return std::nullopt;
  Batch batch;
  batch.samples = std::move(pending_);
  pending_.clear();
  batch.first_index = next_index_;
  batch.watermark_ns = std::max(watermark_ns_, batch.samples.back().stamp_ns);
  next_index_ += batch.samples.size();
  watermark_ns_ = batch.watermark_ns;
  return batch;
}

ImuForwarder::Batch ImuForwarder::silent_until(std::int64_t stamp_ns) {
  Batch batch = take_batch().value_or(Batch{{}, next_index_, watermark_ns_});
  batch.watermark_ns = std::max(batch.watermark_ns, stamp_ns);
  watermark_ns_ = batch.watermark_ns;
  return batch;
}

}  // namespace heslam::ros2
