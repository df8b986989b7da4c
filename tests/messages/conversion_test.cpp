// IDL <-> core conversions (poses, camera input, odometry, keyframes): round trips with known values,
// and map state applied to a mirror.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/keyframe.hpp"
#include "components/messages/map_state.hpp"
#include "components/messages/odometry.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::messages {
namespace {

Pose3 test_pose() {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.5, 0.8).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1.25, -0.5, 3.0);
  return T;
}

// Element loop: GCC 12 warns falsely on Eigen's AVX-512 max reduction of a 4x4.
double max_abs_difference(const Pose3& a, const Pose3& b) {
  double worst = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  return worst;
}

TEST(MessageConversion, PoseRoundTripKeepsTheTransform) {
  const Pose3 T = test_pose();
  const Pose3 back = to_pose(to_message(T));
  EXPECT_LT(max_abs_difference(back, T), 1e-15);
  const msg::Pose pose = to_message(T);
  EXPECT_DOUBLE_EQ(pose.position_m[2], 3.0);
}

TEST(MessageConversion, ZeroQuaternionIsIdentityNotNan) {
  const msg::Pose zero{};
  EXPECT_TRUE(to_pose(zero).matrix().isIdentity());
}

TEST(MessageConversion, CalibrationRoundTripIsExact) {
  msg::StereoCalibration message{};
  message.left = {752, 480, 458.654, 457.296, 367.215, 248.375, heslam_msg_DISTORTION_RADIAL_TANGENTIAL, {}, {}};
  message.right = message.left;
  std::vector<double> distortion{-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  runtime::borrow(message.left.distortion, distortion);
  runtime::borrow(message.right.distortion, distortion);
  const Pose3 T = test_pose();
  for (int i = 0; i < 16; ++i) {
    message.left.T_BS[i] = (i % 5 == 0) ? 1.0 : 0.0;
    message.right.T_BS[i] = T.matrix()(i / 4, i % 4);
  }
  std::string source = "sensor.yaml";
  message.source = runtime::borrow(source);
  message.rate_hz = 20.0;

  const StereoCalibration calibration = to_calibration(message);
  EXPECT_EQ(calibration.left.width_px, 752);
  EXPECT_EQ(calibration.left.fx_px, 458.654);
  EXPECT_EQ(calibration.right.distortion, distortion);
  EXPECT_EQ(calibration.left.distortion_model, DistortionModel::kRadialTangential);
  EXPECT_TRUE(calibration.left.T_BS.matrix().isIdentity());
  EXPECT_EQ(calibration.right.T_BS.matrix(), T.matrix());  // bit for bit: same doubles, same order
  EXPECT_EQ(calibration.source, "sensor.yaml");
  EXPECT_FALSE(calibration.explicit_rectification.has_value());
}

// A fisheye (equidistant) camera keeps its model and its four coefficients on the wire.
TEST(MessageConversion, EquidistantCalibrationRoundTripIsExact) {
  msg::StereoCalibration message{};
  message.left = {752, 480, 330.0, 331.0, 375.5, 239.5, heslam_msg_DISTORTION_EQUIDISTANT, {}, {}};
  message.right = message.left;
  std::vector<double> distortion{0.003482389402, 0.000715034845, -0.002053236141, 0.000202936736};
  runtime::borrow(message.left.distortion, distortion);
  runtime::borrow(message.right.distortion, distortion);
  std::string source = "tum_vi.yaml";
  message.source = runtime::borrow(source);
  const StereoCalibration calibration = to_calibration(message);
  EXPECT_EQ(calibration.left.distortion_model, DistortionModel::kEquidistant);
  EXPECT_EQ(calibration.right.distortion_model, DistortionModel::kEquidistant);
  EXPECT_EQ(calibration.left.distortion, distortion);
}

TEST(MessageConversion, CalibrationWithoutFocalLengthNamesTheSource) {
  msg::StereoCalibration message{};
  std::string source = "bad.yaml";
  message.source = runtime::borrow(source);
  try {
    to_calibration(message);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("bad.yaml"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("left"), std::string::npos) << error.what();
  }
}

TEST(MessageConversion, FrameImagesAreWrappedAndSizesChecked) {
  std::vector<std::uint8_t> left(4 * 3, 7), right(4 * 3, 9);
  msg::StereoFrame frame{};
  frame.width_px = 4;
  frame.height_px = 3;
  frame.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(frame.left, left);
  runtime::borrow(frame.right, right);
  const GreyPair pair = to_grey_images(frame);
  EXPECT_EQ(pair.left.data, left.data());  // no copy
  EXPECT_EQ(pair.right.at<std::uint8_t>(2, 3), 9);

  frame.height_px = 4;  // 16 bytes expected, 12 given
  EXPECT_THROW(to_grey_images(frame), std::runtime_error);

  std::vector<std::uint8_t> bgr(2 * 1 * 3, 0);
  bgr[0] = 255;  // blue pixel
  frame.width_px = 2;
  frame.height_px = 1;
  frame.encoding = heslam_msg_ENCODING_BGR8;
  runtime::borrow(frame.left, bgr);
  runtime::borrow(frame.right, bgr);
  const GreyPair grey = to_grey_images(frame);
  EXPECT_EQ(grey.left.channels(), 1);
  EXPECT_EQ(grey.left.at<std::uint8_t>(0, 0), 29);  // 0.114 * 255, OpenCV's BGR -> grey weights
}

std::string error_of(const msg::StereoFrame& frame) {
  try {
    to_grey_images(frame);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "(no error)";
}

// Known bad frames: the line names the side at fault and prints the wire values as they are.
TEST(MessageConversion, BadFrameSizesNameTheFieldAndTheSide) {
  std::vector<std::uint8_t> full(4 * 3, 7), short_one(4 * 2, 9);
  msg::StereoFrame frame{};
  frame.seq = 12;
  frame.width_px = 4;
  frame.height_px = 3;
  frame.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(frame.left, full);
  runtime::borrow(frame.right, short_one);
  EXPECT_EQ(error_of(frame), "stereo frame 12: expected 12 bytes per image for 4x3x1, right has 8");
  runtime::borrow(frame.left, short_one);
  runtime::borrow(frame.right, full);
  EXPECT_EQ(error_of(frame), "stereo frame 12: expected 12 bytes per image for 4x3x1, left has 8");

  frame.width_px = 0xFFFFFFFFu;
  frame.height_px = 0xFFFFFFFFu;
  EXPECT_EQ(error_of(frame),
            "stereo frame 12: width_px x height_px 4294967295x4294967295: expected 1..8192 px per side");
  frame.width_px = 100000;  // would be 40 GB of pixels and maps if it reached OpenCV
  frame.height_px = 400000;
  EXPECT_EQ(error_of(frame), "stereo frame 12: width_px x height_px 100000x400000: expected 1..8192 px per side");
}

TEST(MessageConversion, CalibrationWithAnImpossibleSizeNamesTheSourceNotOpenCv) {
  msg::StereoCalibration message{};
  message.left = {100000, 100000, 458.654, 457.296, 367.215, 248.375, heslam_msg_DISTORTION_NONE, {}, {}};
  message.right = message.left;
  std::string source = "huge.yaml";
  message.source = runtime::borrow(source);
  try {
    to_calibration(message);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "calibration 'huge.yaml': left: image size 100000x100000: expected 1..8192 px per side");
  }
}

TEST(MessageConversion, OdometryOfALostFrameCarriesNoPose) {
  TrackResult result;
  result.state = TrackingState::kLost;
  result.T_wc = test_pose();
  result.reference_kf = 5;
  const std::vector<StageTiming> timings{{"rectify", 1.5}, {"a_stage_name_much_longer_than_thirty_one_chars", 2.0}};
  const OdometryMessage odometry(100, 3, result, 800, timings);
  const msg::Odometry& message = odometry.get();
  EXPECT_EQ(message.state, heslam_msg_TRACKING_LOST);
  EXPECT_TRUE(to_pose(message.T_wc).matrix().isIdentity());
  EXPECT_EQ(message.reference_keyframe_id, kNoId);
  ASSERT_EQ(message.stage_times._length, 2u);
  EXPECT_STREQ(message.stage_times._buffer[0].stage, "rectify");
  EXPECT_EQ(std::strlen(message.stage_times._buffer[1].stage), 31u);
  EXPECT_FLOAT_EQ(message.stage_times._buffer[1].ms, 2.0f);
}

// Inertial tracking: a frame the IMU carried has a pose (state INERTIAL_ONLY), and odometry carries the
// velocity only when it is set.
TEST(MessageConversion, OdometryOfAnInertialOnlyFrameCarriesItsPoseAndVelocity) {
  TrackResult result;
  result.state = TrackingState::kInertialOnly;
  result.T_wc = test_pose();
  result.reference_kf = 5;
  result.map_id = 1;
  OdometryMessage odometry(100, 3, result, 0, {});
  EXPECT_FALSE(odometry.get().velocity_valid);
  odometry.set_velocity(Eigen::Vector3d(0.5, -1.0, 2.0));
  const msg::Odometry& message = odometry.get();
  EXPECT_EQ(message.state, heslam_msg_TRACKING_INERTIAL_ONLY);
  EXPECT_TRUE(to_pose(message.T_wc).isApprox(test_pose()));
  EXPECT_EQ(message.reference_keyframe_id, 5u);
  EXPECT_EQ(message.map_id, 1u);
  EXPECT_TRUE(message.velocity_valid);
  EXPECT_EQ(message.v_w[0], 0.5);
  EXPECT_EQ(message.v_w[1], -1.0);
  EXPECT_EQ(message.v_w[2], 2.0);
  EXPECT_FALSE(check(message).has_value());
}

Keyframe make_keyframe(KeyframeId id, int keypoints) {
  Keyframe keyframe;
  keyframe.id = id;
  keyframe.stamp_ns = 42;
  keyframe.T_wc = test_pose();
  for (int i = 0; i < keypoints; ++i) {
    keyframe.features.keypoints.push_back(Keypoint{10.f + i, 20.f, 30.f * i, 1.f, i % 8});
    Descriptor d{};
    d.fill(static_cast<std::uint8_t>(i));
    keyframe.features.descriptors.push_back(d);
    keyframe.features.u_right_px.push_back(i % 2 == 0 ? 5.f + i : kNoStereo);
    keyframe.features.depth_m.push_back(i % 2 == 0 ? 2.f : kNoStereo);
    keyframe.point_ids.push_back(i % 2 == 0 ? make_id(kFrontendTag, 100 + i) : kNoId);
  }
  return keyframe;
}

TEST(MessageConversion, KeyframeRoundTripKeepsFeaturesPointsAndNewPoints) {
  Keyframe keyframe = make_keyframe(make_id(kFrontendTag, 3), 6);
  keyframe.map_id = 2;  // the atlas: a keyframe of the third map; its new points are in it too
  MapPoint point;
  point.id = make_id(kFrontendTag, 104);
  point.p_w = Eigen::Vector3d(1, 2, 3);
  point.observations.emplace_back(keyframe.id, 4);
  PinholeStereo camera{435.2, 435.2, 367.4, 252.2, 0.11, 752, 480};
  const KeyframeId reference = make_id(kFrontendTag, 2);
  const KeyframeMessage message(keyframe, 17, {point}, camera, reference, 41);
  EXPECT_EQ(message.get().frame_seq, 17u);
  EXPECT_EQ(message.get().map_id, 2u);
  EXPECT_EQ(message.get().camera.baseline_m, 0.11);

  const DecodedKeyframe decoded = to_keyframe(message.get());
  EXPECT_EQ(decoded.keyframe.id, keyframe.id);
  EXPECT_EQ(decoded.keyframe.map_id, 2u);
  EXPECT_EQ(decoded.reference_kf, reference);
  EXPECT_EQ(decoded.tracked_map_version, 41u);
  EXPECT_EQ(decoded.keyframe.point_ids, keyframe.point_ids);
  ASSERT_EQ(decoded.keyframe.features.size(), 6u);
  EXPECT_EQ(decoded.keyframe.features.descriptors[5], keyframe.features.descriptors[5]);
  EXPECT_EQ(decoded.keyframe.features.keypoints[3].octave, 3);
  EXPECT_EQ(decoded.keyframe.features.keypoints[3].angle_deg, 90.f);
  EXPECT_EQ(decoded.keyframe.features.depth_m[1], kNoStereo);
  EXPECT_EQ(decoded.keyframe.features.pyramid.levels, 8);
  ASSERT_EQ(decoded.new_points.size(), 1u);
  EXPECT_EQ(decoded.new_points[0].p_w, point.p_w);
  EXPECT_EQ(decoded.new_points[0].map_id, 2u);
  EXPECT_EQ(decoded.new_points[0].observations.front(), std::make_pair(keyframe.id, 4));
}

TEST(MessageConversion, MirrorAppliesKeyframeStateAndPointMerges) {
  Map map;
  const Keyframe keyframe = make_keyframe(make_id(kFrontendTag, 1), 4);
  map.keyframes[keyframe.id] = keyframe;
  const PointId a = keyframe.point_ids[0];
  const PointId b = keyframe.point_ids[2];
  map.points[a].id = a;
  map.points[a].observations.emplace_back(keyframe.id, 0);
  map.points[b].id = b;
  map.points[b].observations.emplace_back(keyframe.id, 2);

  msg::KeyframeState state{};
  state.id = keyframe.id;
  state.map_version = 7;
  state.map_id = 4;
  Pose3 refined = test_pose();
  refined.translation().x() += 0.01;
  state.T_wc = to_message(refined);
  std::vector<msg::CovisibleKeyframe> covisible{{make_id(kFrontendTag, 2), 33}};
  runtime::borrow(state.covisible, covisible);
  ASSERT_TRUE(apply_keyframe_state(map, state));
  EXPECT_NEAR(map.keyframes[keyframe.id].T_wc.translation().x(), refined.translation().x(), 1e-15);
  EXPECT_EQ(map.keyframes[keyframe.id].covisible.front(), std::make_pair(make_id(kFrontendTag, 2), 33));
  EXPECT_EQ(map.keyframes[keyframe.id].map_id, 4u);
  EXPECT_EQ(map.version, 0u);  // only the mapper's version markers advance it (MirrorVersion)
  EXPECT_FALSE(is_version_marker(state));
  state.id = 999;
  EXPECT_FALSE(apply_keyframe_state(map, state));

  // Point a merged into b: a disappears. b already sees the keyframe (keypoint 2), so keypoint 0 sees
  // nothing, as in the mapper (replace_point): a keyframe never sees one point twice.
  msg::MapPointState merged{};
  merged.id = a;
  merged.merged_into = b;
  apply_point_state(map, merged);
  EXPECT_EQ(map.point(a), nullptr);
  EXPECT_EQ(map.keyframes[keyframe.id].point_ids[0], kNoId);
  EXPECT_EQ(map.keyframes[keyframe.id].point_ids[2], b);

  // A point the mapper triangulated appears with its observation.
  msg::MapPointState created{};
  created.id = make_id(kMapperTag, 1);
  created.position_w_m[2] = 4.0;
  created.map_id = 4;
  created.descriptor[0] = 0xAB;
  std::vector<msg::PointObservation> observations{{keyframe.id, 1}};
  runtime::borrow(created.observations, observations);
  apply_point_state(map, created);
  ASSERT_NE(map.point(created.id), nullptr);
  EXPECT_EQ(map.point(created.id)->p_w.z(), 4.0);
  EXPECT_EQ(map.point(created.id)->descriptor[0], 0xAB);
  EXPECT_EQ(map.point(created.id)->map_id, 4u);
  EXPECT_EQ(map.keyframes[keyframe.id].point_ids[1], created.id);

  erase_point(map, b);
  EXPECT_EQ(map.keyframes[keyframe.id].point_ids[0], kNoId);
  EXPECT_EQ(map.keyframes[keyframe.id].point_ids[2], kNoId);
}

}  // namespace
}  // namespace heslam::messages
