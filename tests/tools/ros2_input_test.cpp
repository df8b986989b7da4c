// heslam-ros2-input's conversions on known values: two ROS 2 CameraInfo -> heslam's calibration (raw
// images with an explicit rectification, or images already rectified), sensor_msgs/Image -> packed
// MONO8 / BGR8, sensor_msgs/Imu -> readings (orientation-only IMUs refused by name, stamps going
// backwards refused), the IMU calibration from EuRoC and Kalibr files, and every refusal one line naming
// the topic (or file) and the field.
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "components/core/camera/stereo_rectifier.hpp"
#include "runtime/config.hpp"
#include "runtime/sequence.hpp"
#include "test_support.hpp"
#include "tools/dataset/imu_reader.hpp"
#include "tools/ros2_bridge/ros2_input.hpp"
#include "tools/ros2_bridge/ros2_input_conversions.hpp"

namespace heslam::ros2 {
namespace {

const std::string kLeftTopic = "stereo/left/camera_info";
const std::string kRightTopic = "stereo/right/camera_info";
const std::string kPlumbBob = "plumb_bob";
const std::string kRational = "rational_polynomial";
constexpr double kBaselineM = 0.11;

// A stereo pair's CameraInfo as a ROS 2 stereo calibration writes it: the rectifying rotations turn
// each camera about y, P is the common rectified pinhole, the right one's P[0][3] = -fx * baseline.
struct CameraInfos {
  std::vector<double> d_left{-0.28, 0.07, 0.0002, 0.00002, 0.0};
  std::vector<double> d_right{-0.28, 0.07, -0.0001, 0.00003, 0.0};
  CameraInfo left{};
  CameraInfo right{};

  CameraInfos() {
    fill(left, d_left, 0.010, 0.0);
    fill(right, d_right, -0.004, -435.0 * kBaselineM);
  }

  static void fill(CameraInfo& info, std::vector<double>& d, double angle_rad, double p03) {
    info.width = 752;
    info.height = 480;
    info.distortion_model = runtime::borrow(kPlumbBob);
    runtime::borrow(info.d, d);
    const double k[9] = {458.0, 0.0, 367.0, 0.0, 457.0, 248.0, 0.0, 0.0, 1.0};
    std::copy(std::begin(k), std::end(k), info.k);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) info.r[3 * r + c] = R(r, c);
    }
    const double p[12] = {435.0, 0.0, 370.0, p03, 0.0, 435.0, 250.0, 0.0, 0.0, 0.0, 1.0, 0.0};
    std::copy(std::begin(p), std::end(p), info.p);
  }
};

std::string refusal(const CameraInfos& infos, bool rectified) {
  try {
    to_stereo_calibration({infos.left, kLeftTopic}, {infos.right, kRightTopic}, rectified);
  } catch (const std::exception& error) {
    return error.what();
  }
  return "";
}

TEST(Ros2Input, RawCameraInfoBecomesAnExplicitRectificationWithTheBaseline) {
  const CameraInfos infos;
  const StereoCalibration calibration =
      to_stereo_calibration({infos.left, kLeftTopic}, {infos.right, kRightTopic}, false);
  EXPECT_FALSE(calibration.input_rectified);
  ASSERT_TRUE(calibration.explicit_rectification.has_value());
  EXPECT_EQ(calibration.left.fx_px, 458.0);
  EXPECT_EQ(calibration.left.cy_px, 248.0);
  EXPECT_EQ(calibration.left.distortion, infos.d_left);
  EXPECT_EQ(calibration.left.distortion_model, DistortionModel::kRadialTangential);
  // Left -> right: the right camera sits at +baseline in the rectified frames, turned by R_r^T R_l.
  const Pose3 T_rl = calibration.T_rl();
  const Eigen::Matrix3d expected_R =
      Eigen::AngleAxisd(0.010 - (-0.004), Eigen::Vector3d::UnitY()).toRotationMatrix();  // R_right^T R_left
  EXPECT_LT((T_rl.rotation() - expected_R).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(T_rl.inverse().translation().norm(), kBaselineM, 1e-12);
  // heslam's rectification of it uses ROS 2's P: the same rectified pinhole and baseline.
  const StereoRectifier rectifier(calibration);
  EXPECT_NEAR(rectifier.camera().fx_px, 435.0, 1e-9);
  EXPECT_NEAR(rectifier.camera().baseline_m, kBaselineM, 1e-9);
}

TEST(Ros2Input, RectifiedImagesUseTheProjection) {
  const CameraInfos infos;
  const StereoCalibration calibration =
      to_stereo_calibration({infos.left, kLeftTopic}, {infos.right, kRightTopic}, true);
  EXPECT_TRUE(calibration.input_rectified);
  EXPECT_EQ(calibration.left.fx_px, 435.0);
  EXPECT_EQ(calibration.left.cx_px, 370.0);
  EXPECT_TRUE(calibration.left.distortion.empty());
  EXPECT_NEAR(calibration.right.T_BS.translation().x(), kBaselineM, 1e-12);
}

TEST(Ros2Input, RationalPolynomialWithZeroHigherTermsIsPlumbBob) {
  CameraInfos infos;
  std::vector<double> eight{-0.28, 0.07, 0.0002, 0.00002, 0.001, 0.0, 0.0, 0.0};
  infos.left.distortion_model = runtime::borrow(kRational);
  runtime::borrow(infos.left.d, eight);
  const StereoCalibration calibration =
      to_stereo_calibration({infos.left, kLeftTopic}, {infos.right, kRightTopic}, false);
  EXPECT_EQ(calibration.left.distortion, std::vector<double>(eight.begin(), eight.begin() + 5));
  eight[6] = 0.01;
  EXPECT_EQ(refusal(infos, false),
            "topic 'stereo/left/camera_info': field d: rational_polynomial k4..k6 must be 0: heslam models "
            "plumb_bob (k1 k2 p1 p2 k3) only");
}

// A fisheye pair (camera_calibration --fisheye): the equidistant model, rectified with ROS 2's R and P.
TEST(Ros2Input, EquidistantCameraInfoIsAFisheyePairRectifiedByItsProjection) {
  CameraInfos infos;
  const std::string equidistant = "equidistant";
  std::vector<double> left_k{-0.012, 0.004, -0.0008, 0.0001};
  std::vector<double> right_k{-0.011, 0.003, -0.0007, 0.0001};
  infos.left.distortion_model = runtime::borrow(equidistant);
  infos.right.distortion_model = runtime::borrow(equidistant);
  runtime::borrow(infos.left.d, left_k);
  runtime::borrow(infos.right.d, right_k);
  const StereoCalibration calibration =
      to_stereo_calibration({infos.left, kLeftTopic}, {infos.right, kRightTopic}, false);
  EXPECT_EQ(calibration.left.distortion_model, DistortionModel::kEquidistant);
  EXPECT_EQ(calibration.right.distortion, right_k);
  const StereoRectifier rectifier(calibration);
  EXPECT_NEAR(rectifier.camera().fx_px, 435.0, 1e-9);
  EXPECT_NEAR(rectifier.camera().baseline_m, kBaselineM, 1e-9);
  std::vector<double> five{-0.012, 0.004, -0.0008, 0.0001, 0.0};
  runtime::borrow(infos.left.d, five);
  EXPECT_EQ(refusal(infos, false),
            "topic 'stereo/left/camera_info': field d: expected 4 equidistant coefficients k1 k2 k3 k4");
}

TEST(Ros2Input, BadCameraInfoIsOneLineNamingTopicAndField) {
  {
    CameraInfos infos;
    const std::string fov = "fov";
    infos.right.distortion_model = runtime::borrow(fov);
    EXPECT_EQ(refusal(infos, false),
              "topic 'stereo/right/camera_info': field distortion_model: 'fov': expected plumb_bob, "
              "rational_polynomial (with k4..k6 = 0) or equidistant");
  }
  {
    CameraInfos infos;
    infos.right.p[3] = 0.0;  // a left camera's P on the right topic (a swapped pair)
    EXPECT_EQ(refusal(infos, false),
              "topic 'stereo/right/camera_info': field p: expected P[0][3] = -fx * baseline < 0 (the right camera)");
  }
  {
    CameraInfos infos;
    infos.right.width = 640;
    EXPECT_EQ(refusal(infos, false),
              "topic 'stereo/right/camera_info': field width/height: expected the left camera's size");
  }
  {
    CameraInfos infos;
    infos.left.r[0] = 2.0;
    EXPECT_NE(refusal(infos, false).find("topic 'stereo/left/camera_info': field r: expected a rotation"),
              std::string::npos);
  }
}

Image image_of(const std::string& encoding, std::uint32_t width, std::uint32_t height, std::uint32_t step,
               std::vector<std::uint8_t>& data) {
  Image image{};
  image.encoding = runtime::borrow(encoding);
  image.width = width;
  image.height = height;
  image.step = step;
  runtime::borrow(image.data, data);
  return image;
}

TEST(Ros2Input, ImagesArePackedAndRgbBecomesBgr) {
  const std::string rgb8 = "rgb8", mono8 = "mono8";
  // 2x2 rgb8 with 2 bytes of row padding (step 8).
  std::vector<std::uint8_t> rgb{1, 2, 3, 4, 5, 6, 0, 0, 7, 8, 9, 10, 11, 12, 0, 0};
  const PackedImage colour = to_packed_image(image_of(rgb8, 2, 2, 8, rgb), "stereo/left/image_raw", 2, 2);
  EXPECT_EQ(colour.encoding, heslam_msg_ENCODING_BGR8);
  EXPECT_EQ(colour.pixels, (std::vector<std::uint8_t>{3, 2, 1, 6, 5, 4, 9, 8, 7, 12, 11, 10}));
  std::vector<std::uint8_t> grey{10, 20, 30, 40, 50, 60};
  const PackedImage mono = to_packed_image(image_of(mono8, 3, 2, 3, grey), "stereo/left/image_raw", 0, 0);
  EXPECT_EQ(mono.encoding, heslam_msg_ENCODING_MONO8);
  EXPECT_EQ(mono.pixels, grey);
}

std::string image_refusal(const Image& image, std::uint32_t width, std::uint32_t height) {
  try {
    to_packed_image(image, "stereo/left/image_raw", width, height);
  } catch (const std::exception& error) {
    return error.what();
  }
  return "";
}

TEST(Ros2Input, BadImagesAreOneLineNamingTopicAndField) {
  const std::string yuv = "yuv422", mono8 = "mono8", bgr8 = "bgr8";
  std::vector<std::uint8_t> data(12, 0);
  EXPECT_EQ(image_refusal(image_of(yuv, 3, 2, 6, data), 0, 0),
            "topic 'stereo/left/image_raw': field encoding: 'yuv422': expected mono8, bgr8 or rgb8");
  EXPECT_EQ(image_refusal(image_of(mono8, 6, 2, 6, data), 752, 480),
            "topic 'stereo/left/image_raw': field width/height: 6x2 differs from the CameraInfo's 752x480");
  // A bgr8 header on mono8 bytes (an encoding mixup): the step cannot hold the row.
  EXPECT_EQ(image_refusal(image_of(bgr8, 6, 2, 6, data), 0, 0),
            "topic 'stereo/left/image_raw': field step: 6 is less than width x channels = 18");
  EXPECT_EQ(image_refusal(image_of(mono8, 6, 3, 6, data), 0, 0),
            "topic 'stereo/left/image_raw': field data: 12 bytes, expected step x height = 18");
}

PackedImage grey_image(std::uint8_t value) {
  PackedImage image;
  image.width_px = 1;
  image.height_px = 1;
  image.pixels = {value};
  return image;
}

// Left and right meet by stamp in any order; an image whose partner never came is dropped and counted
// once a later pair is made; a stamp not after the last pair's is refused with a line.
TEST(Ros2Input, PairsByStampCountsUnpairedAndRefusesStampsGoingBackwards) {
  using Side = StereoPairer::Side;
  StereoPairer pairer;
  EXPECT_FALSE(pairer.add(Side::kLeft, 100, grey_image(1)));
  const std::optional<StereoPairer::Pair> first = pairer.add(Side::kRight, 100, grey_image(2));
  ASSERT_TRUE(first);
  EXPECT_EQ(first->stamp_ns, 100);
  EXPECT_EQ(first->left.pixels[0], 1);
  EXPECT_EQ(first->right.pixels[0], 2);
  EXPECT_FALSE(pairer.add(Side::kLeft, 200, grey_image(3)));  // its right image is lost
  EXPECT_FALSE(pairer.add(Side::kRight, 300, grey_image(4)));
  const std::optional<StereoPairer::Pair> second = pairer.add(Side::kLeft, 300, grey_image(5));
  ASSERT_TRUE(second);
  EXPECT_EQ(second->left.pixels[0], 5);
  EXPECT_EQ(second->right.pixels[0], 4);
  EXPECT_EQ(pairer.unpaired(), 1u);
  try {
    pairer.add(Side::kRight, 250, grey_image(6));
    ADD_FAILURE() << "a stamp before the last pair's was taken";
  } catch (const std::exception& error) {
    EXPECT_EQ(std::string(error.what()),
              "stamp 250 ns is not after the last pair's 300 ns (stamps going backwards, or too late)");
  }
  // A side that runs ahead keeps at most kMaxPending images.
  for (std::int64_t stamp = 400; stamp < 400 + 10 * 10; stamp += 10) pairer.add(Side::kLeft, stamp, grey_image(7));
  EXPECT_EQ(pairer.unpaired(), 1u + 10u - StereoPairer::kMaxPending);
}

// Frames of which no image came are read from the gaps in the stamps against the camera's period: a
// 20 Hz camera with +-2 ms jitter, both images of frames 1, 10 and 20-22 lost, the right image of frame 30
// only (the pairer counts that one): 5 frames never received, each found at the next image's stamp.
TEST(Ros2Input, FramesOfWhichNoImageCameAreCountedFromTheGapsInTheStamps) {
  constexpr std::int64_t kPeriod = 50'000'000;
  const auto stamp = [](int frame) { return 1'000'000'000 + frame * kPeriod + (frame % 3 - 1) * 2'000'000; };
  FrameGapCounter gaps;
  std::uint64_t found_at_frame_2 = 0, found_at_frame_4 = 0, found_at_frame_11 = 0, found_at_frame_23 = 0;
  for (int frame = 0; frame < 40; ++frame) {
    if (frame == 1 || frame == 10 || (frame >= 20 && frame <= 22)) continue;
    std::uint64_t found = 0;
    if (frame != 30) found += gaps.add(stamp(frame));  // left
    found += gaps.add(stamp(frame));                   // right: the same stamp, ignored after the left
    EXPECT_EQ(gaps.add(stamp(frame) - 1), 0u);         // a stamp not after the newest: ignored
    if (frame == 2) found_at_frame_2 = found;
    if (frame == 4) found_at_frame_4 = found;  // the third interval: the first ones judged
    if (frame == 11) found_at_frame_11 = found;
    if (frame == 23) found_at_frame_23 = found;
  }
  EXPECT_EQ(found_at_frame_2, 0u);  // not judged yet
  EXPECT_EQ(found_at_frame_4, 1u);  // frame 1, between frames 0 and 2
  EXPECT_EQ(found_at_frame_11, 1u);
  EXPECT_EQ(found_at_frame_23, 3u);
  EXPECT_EQ(gaps.missing(), 5u);
  EXPECT_NEAR(static_cast<double>(gaps.period_ns()), static_cast<double>(kPeriod), 4'000'000.0);
}

// A left driver in mono8 and a right one in colour: the pair is refused naming both topics.
TEST(Ros2Input, PairMixingMonoAndColourIsOneLineNamingBothTopics) {
  StereoPairer::Pair pair;
  pair.stamp_ns = 42;
  pair.left.encoding = heslam_msg_ENCODING_MONO8;
  pair.right.encoding = heslam_msg_ENCODING_BGR8;
  try {
    check_same_encoding(pair, "rt/left", "rt/right");
    ADD_FAILURE() << "a mixed pair was taken";
  } catch (const std::exception& error) {
    EXPECT_EQ(std::string(error.what()),
              "topics 'rt/left' and 'rt/right': field encoding: the pair at stamp 42 ns mixes mono8 (left) and bgr8 "
              "(right): pair dropped");
  }
  pair.right.encoding = heslam_msg_ENCODING_MONO8;
  EXPECT_NO_THROW(check_same_encoding(pair, "rt/left", "rt/right"));
}

const std::string kImuTopic = "rt/imu/data";

Imu imu_message(std::int32_t sec, std::uint32_t nanosec) {
  Imu imu{};
  imu.header.stamp.sec = sec;
  imu.header.stamp.nanosec = nanosec;
  imu.orientation.w = 1.0;
  imu.orientation_covariance[0] = -1.0;  // no orientation: fine, heslam does not use it
  imu.angular_velocity = {0.1, -0.2, 0.3};
  imu.linear_acceleration = {0.5, 9.7, -0.25};
  return imu;
}

template <typename Error = std::runtime_error, typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const Error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(Ros2InputImu, ImuMessageBecomesAReading) {
  const ImuSample sample = to_imu_sample(imu_message(12, 345), kImuTopic);
  EXPECT_EQ(sample.stamp_ns, 12'000'000'345);
  EXPECT_EQ(sample.gyro_rad_s, Eigen::Vector3d(0.1, -0.2, 0.3));
  EXPECT_EQ(sample.accel_m_s2, Eigen::Vector3d(0.5, 9.7, -0.25));
}

// REP 145: covariance[0] = -1 says the field is not given. Without linear acceleration (or angular
// velocity) the IMU cannot serve inertial tracking: refused by name, as a sensor, not as a reading.
TEST(Ros2InputImu, OrientationOnlyImuIsRefusedByName) {
  Imu imu = imu_message(1, 0);
  imu.linear_acceleration_covariance[0] = -1.0;
  EXPECT_EQ(error_of<UnusableImu>([&] { to_imu_sample(imu, kImuTopic); }),
            "topic 'rt/imu/data': field linear_acceleration_covariance[0] is -1: the IMU gives no linear "
            "acceleration (an orientation-only IMU); heslam's inertial tracking needs angular velocity and "
            "linear acceleration");
  imu = imu_message(1, 0);
  imu.angular_velocity_covariance[0] = -1.0;
  EXPECT_NE(
      error_of<UnusableImu>([&] { to_imu_sample(imu, kImuTopic); }).find("field angular_velocity_covariance[0] is -1"),
      std::string::npos);
}

TEST(Ros2InputImu, BadReadingsAreOneLineNamingTopicAndField) {
  Imu imu = imu_message(1, 0);
  imu.linear_acceleration.y = std::numeric_limits<double>::quiet_NaN();
  const std::string nan_line = error_of([&] { to_imu_sample(imu, kImuTopic); });
  EXPECT_EQ(nan_line.rfind("topic 'rt/imu/data': field linear_acceleration: not a finite number", 0), 0u) << nan_line;
  imu = imu_message(1, 0);
  imu.angular_velocity.x = std::numeric_limits<double>::infinity();
  EXPECT_NE(error_of([&] { to_imu_sample(imu, kImuTopic); }).find("field angular_velocity: not a finite"),
            std::string::npos);
  imu = imu_message(-3, 0);
  EXPECT_EQ(error_of([&] { to_imu_sample(imu, kImuTopic); }),
            "topic 'rt/imu/data': field header.stamp: negative (-3 s): reading dropped");
}

// Batches carry the readings since the last one, watermark = their last stamp; a stamp going backwards,
// a repeat, or a reading older than a frame already let go without it is refused, nothing changed.
TEST(Ros2InputImu, ForwarderWatermarksAndRefusesStampsGoingBackwards) {
  ImuForwarder forwarder;
  EXPECT_FALSE(forwarder.take_batch());
  ImuSample sample;
  sample.stamp_ns = 10;
  forwarder.add(sample);
  sample.stamp_ns = 20;
  forwarder.add(sample);
  std::optional<ImuForwarder::Batch> batch = forwarder.take_batch();
  ASSERT_TRUE(batch);
  EXPECT_EQ(batch->samples.size(), 2u);
  EXPECT_EQ(batch->first_index, 0u);
  EXPECT_EQ(batch->watermark_ns, 20);
  sample.stamp_ns = 15;
  EXPECT_EQ(error_of([&] { forwarder.add(sample); }),
            "stamp 15 ns goes backwards (last reading 20 ns): reading dropped");
  sample.stamp_ns = 20;
  EXPECT_EQ(error_of([&] { forwarder.add(sample); }), "stamp 20 ns repeats the last reading's: reading dropped");
  EXPECT_FALSE(forwarder.take_batch());
  // A frame at 50 waited too long: the IMU is declared silent up to it.
  const ImuForwarder::Batch silent = forwarder.silent_until(50);
  EXPECT_TRUE(silent.samples.empty());
  EXPECT_EQ(silent.first_index, 2u);
  EXPECT_EQ(silent.watermark_ns, 50);
  sample.stamp_ns = 40;
  EXPECT_EQ(error_of([&] { forwarder.add(sample); }),
            "stamp 40 ns is at or before 50 ns, up to which frames already went out: reading dropped");
  sample.stamp_ns = 60;
  forwarder.add(sample);
  batch = forwarder.take_batch();
  ASSERT_TRUE(batch);
  EXPECT_EQ(batch->first_index, 2u);
  EXPECT_EQ(batch->watermark_ns, 60);
  EXPECT_EQ(forwarder.taken(), 3u);
}

// Known files: the IMU 0.1 m ahead of and rotated 90 deg about z from the left camera.
struct ImuFiles {
  test::ScratchDir dir{"ros2_input_imu_files"};
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::ofstream(dir.path() / name) << text;
    return dir.path() / name;
  }
};

constexpr const char* kEurocImu = R"(%YAML:1.0
sensor_type: imu
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0,
         0.0, 1.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 200
gyroscope_noise_density: 1.6968e-04
gyroscope_random_walk: 1.9393e-05
accelerometer_noise_density: 2.0000e-3
accelerometer_random_walk: 3.0000e-3
)";

// cam0 -> body (the IMU): camera x = body y, camera y = -body x, at (0.1, 0, 0) in the body.
constexpr const char* kEurocCam0 = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [0.0, -1.0, 0.0, 0.1,
         1.0, 0.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
)";

TEST(Ros2InputImu, CalibrationFromEurocSensorFiles) {
  const ImuFiles files;
  const ImuCalibration calibration =
      load_ros2_imu_calibration(files.write("imu.yaml", kEurocImu), files.write("cam0.yaml", kEurocCam0));
  EXPECT_EQ(calibration.rate_hz, 200.0);
  EXPECT_EQ(calibration.noise.gyro_noise_density, 1.6968e-04);
  EXPECT_EQ(calibration.noise.gyro_random_walk, 1.9393e-05);
  EXPECT_EQ(calibration.noise.accel_noise_density, 2.0e-3);
  EXPECT_EQ(calibration.noise.accel_random_walk, 3.0e-3);
  EXPECT_EQ(calibration.time_offset_ns, 0);
  // T_BS (IMU -> the input's body, the left camera) = T_BS(cam0)^-1 = [R^T, -R^T t]: the IMU's origin
  // is at (0, 0.1, 0) in the camera and its x axis is the camera's -y.
  EXPECT_LT((calibration.T_BS.translation() - Eigen::Vector3d(0.0, 0.1, 0.0)).norm(), 1e-12);
  EXPECT_LT((calibration.T_BS.linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0.0, -1.0, 0.0)).norm(), 1e-12);
}

TEST(Ros2InputImu, CalibrationFromKalibrFiles) {
  const ImuFiles files;
  const auto imu = files.write("imu.yaml", R"(#Accelerometers
accelerometer_noise_density: 1.86e-03
accelerometer_random_walk: 4.33e-04
#Gyroscopes
gyroscope_noise_density: 1.87e-04
gyroscope_random_walk: 2.66e-05
rostopic: /imu0
update_rate: 400.0
)");
  const auto camchain = files.write("camchain-imucam.yaml", R"(cam0:
  T_cam_imu:
  - [0.0, 1.0, 0.0, 0.02]
  - [-1.0, 0.0, 0.0, -0.03]
  - [0.0, 0.0, 1.0, 0.04]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  timeshift_cam_imu: 0.0021
cam1:
  camera_model: pinhole
)");
  const ImuCalibration calibration = load_ros2_imu_calibration(imu, camchain);
  EXPECT_EQ(calibration.rate_hz, 400.0);
  EXPECT_EQ(calibration.noise.accel_noise_density, 1.86e-03);
  EXPECT_EQ(calibration.noise.gyro_random_walk, 2.66e-05);
  EXPECT_EQ(calibration.time_offset_ns, 2'100'000);
  EXPECT_EQ(calibration.T_BS.translation(), Eigen::Vector3d(0.02, -0.03, 0.04));
  EXPECT_EQ(calibration.T_BS.linear() * Eigen::Vector3d::UnitX(), Eigen::Vector3d(0.0, -1.0, 0.0));
}

TEST(Ros2InputImu, BadCalibrationFilesAreOneLineNamingFileAndField) {
  const ImuFiles files;
  const auto cam0 = files.write("cam0.yaml", kEurocCam0);
  std::string no_noise = kEurocImu;
  no_noise.replace(no_noise.find("gyroscope_random_walk"), 4, "gyrX");
  const auto imu = files.write("imu.yaml", no_noise);
  EXPECT_EQ(error_of([&] { load_ros2_imu_calibration(imu, cam0); }),
            imu.string() + ": gyroscope_random_walk: missing (expected a positive number)");
  std::string no_rate = kEurocImu;
  no_rate.replace(no_rate.find("rate_hz"), 7, "rate_xx");
  const auto imu_no_rate = files.write("imu_no_rate.yaml", no_rate);
  EXPECT_EQ(error_of([&] { load_ros2_imu_calibration(imu_no_rate, cam0); }),
            imu_no_rate.string() + ": rate_hz (EuRoC) or update_rate (Kalibr): missing");
  const auto good_imu = files.write("good_imu.yaml", kEurocImu);
  const auto camchain =
      files.write("camchain.yaml", "cam0:\n  camera_model: pinhole\ncam1:\n  camera_model: pinhole\n");
  EXPECT_EQ(error_of([&] { load_ros2_imu_calibration(good_imu, camchain); }),
            camchain.string() + ": cam0.T_cam_imu: missing (a camchain of kalibr_calibrate_imu_camera has it)");
  std::string sheared = kEurocCam0;
  sheared.replace(sheared.find("[0.0, -1.0"), 10, "[0.5, -1.0");
  const auto bad_cam0 = files.write("bad_cam0.yaml", sheared);
  EXPECT_EQ(error_of([&] { load_ros2_imu_calibration(good_imu, bad_cam0); }),
            bad_cam0.string() + ": T_BS: expected a rigid transform (a rotation and a translation)");
  const auto missing = files.dir.path() / "missing.yaml";
  EXPECT_EQ(error_of([&] { load_ros2_imu_calibration(missing, cam0); }),
            missing.string() + ": cannot open (expected an IMU sensor.yaml (EuRoC) or imu.yaml (Kalibr))");
}

// One reader of the noise model (tools/dataset/imu_reader.hpp): heslam-ros2-input and the replay's
// sensor.yaml reader give the same line for the same bad file.
TEST(Ros2InputImu, NoiseModelErrorsAreTheReplaysOwn) {
  const ImuFiles files;
  const auto cam0 = files.write("cam0.yaml", kEurocCam0);
  std::string negative = kEurocImu;
  negative.replace(negative.find("1.9393e-05"), 10, "-1.0");
  const auto imu = files.write("imu.yaml", negative);
  const std::string expected = imu.string() + ": gyroscope_random_walk: expected a positive number, got -1.000000";
  EXPECT_EQ(error_of([&] { load_ros2_imu_calibration(imu, cam0); }), expected);
  EXPECT_EQ(error_of([&] { read_imu_sensor_yaml(imu); }), expected);
}

TEST(Ros2InputImu, ImuFlagsComeTogether) {
  const runtime::Config none = runtime::Config::empty();
  EXPECT_TRUE(InputOptions::from(none, {}).imu_topic.empty());
  const InputOptions options = InputOptions::from(
      none, {"--imu-topic", "imu0", "--imu-calibration", "imu.yaml", "--imu-extrinsic", "camchain.yaml"});
  EXPECT_EQ(options.imu_topic, "imu0");
  EXPECT_EQ(options.imu_calibration, "imu.yaml");
  EXPECT_EQ(error_of([&] {
              InputOptions::from(none, {"--imu-topic", "imu0", "--imu-calibration", "imu.yaml"});
            }),
            "--imu-topic imu0: needs --imu-calibration FILE (the noise model) and --imu-extrinsic FILE (camera "
            "<- IMU), which sensor_msgs/Imu does not carry (docs/ros2.md)");
  EXPECT_EQ(error_of([&] {
              InputOptions::from(none, {"--imu-calibration", "imu.yaml"});
            }),
            "--imu-calibration / --imu-extrinsic: given without --imu-topic");
  EXPECT_NE(error_of([&] {
              InputOptions::from(none, {"--imu-topic", "/imu0/", "--imu-calibration", "a", "--imu-extrinsic", "b"});
            }).find("--imu-topic: '/imu0/'"),
            std::string::npos);
}

}  // namespace
}  // namespace heslam::ros2
