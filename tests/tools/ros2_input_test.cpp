// heslam-ros2-input's conversions on known values: two ROS 2 CameraInfo -> heslam's calibration (raw
// images with an explicit rectification, or images already rectified), sensor_msgs/Image -> packed
// MONO8 / BGR8, and every refusal one line naming the topic and the field.
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "components/core/camera/stereo_rectifier.hpp"
#include "runtime/sequence.hpp"
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

TEST(Ros2Input, BadCameraInfoIsOneLineNamingTopicAndField) {
  {
    CameraInfos infos;
    const std::string equidistant = "equidistant";
    infos.right.distortion_model = runtime::borrow(equidistant);
    EXPECT_EQ(refusal(infos, false),
              "topic 'stereo/right/camera_info': field distortion_model: 'equidistant': expected plumb_bob or "
              "rational_polynomial (with k4..k6 = 0)");
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

}  // namespace
}  // namespace heslam::ros2
