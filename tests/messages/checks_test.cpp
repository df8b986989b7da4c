// messages::check: what every subscriber refuses — NaN / infinite / absurd
// numbers, zero ids, inconsistent sizes, unknown enum values — and that what heslam itself writes
// passes (the version markers, identity poses, the "no pose" all-zero pose).
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/map/ids.hpp"
#include "components/messages/checks.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::messages {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

msg::Pose identity() {
  msg::Pose pose{};
  pose.orientation_xyzw[3] = 1.0;
  return pose;
}

std::string problem(const std::optional<std::string>& result) { return result.value_or("(none)"); }

TEST(MessageChecks, PosesMustBeFiniteBoundedAndUnit) {
  EXPECT_FALSE(check(identity(), "T_wc"));
  EXPECT_FALSE(check(msg::Pose{}, "T_wc"));  // all zero: "no pose", read as identity
  msg::Pose pose = identity();
  pose.position_m[1] = kNaN;
  EXPECT_EQ(problem(check(pose, "T_wc")), "T_wc.position_m[1] is nan, expected a finite number");
  pose = identity();
  pose.position_m[2] = 1e9;
  EXPECT_NE(problem(check(pose, "T_wc")).find("T_wc.position_m[2] is 1e+09"), std::string::npos);
  pose = identity();
  pose.orientation_xyzw[0] = kInf;
  EXPECT_NE(problem(check(pose, "T_wc")).find("orientation_xyzw[0] is inf"), std::string::npos);
  pose = identity();
  pose.orientation_xyzw[3] = 3.0;
  EXPECT_NE(problem(check(pose, "T_wc")).find("norm 3"), std::string::npos);
}

TEST(MessageChecks, OdometryWithANanPoseOrUnknownStateIsRefused) {
  msg::Odometry odometry{};
  odometry.T_wc = odometry.T_ref_c = identity();
  odometry.state = heslam_msg_TRACKING_OK;
  EXPECT_FALSE(check(odometry));
  odometry.T_ref_c.position_m[0] = kNaN;
  EXPECT_NE(problem(check(odometry)).find("T_ref_c.position_m[0] is nan"), std::string::npos);
  odometry.T_ref_c = identity();
  // As a sample from the wire holds it: 7 is no value of the C++ enum, so it is stored as bytes
  // (a cast would be undefined behaviour, which UBSan reports; runtime/wire_enum.hpp).
  runtime::set_wire_value(odometry.state, 7);
  EXPECT_NE(problem(check(odometry)).find("state 7"), std::string::npos);
  runtime::set_wire_value(odometry.state, 0xFFFFFFFF);
  EXPECT_NE(problem(check(odometry)).find("state 4294967295 is not a TrackingState"), std::string::npos);
}

TEST(MessageChecks, KeyframeSizesIdsAndNumbers) {
  std::vector<msg::KeyframeKeypoint> keypoints{{10.f, 20.f, 5.f, 2.f, 90.f, 1}};
  std::vector<std::uint8_t> descriptors(32, 0);
  std::vector<std::uint64_t> point_ids{0};
  msg::Keyframe keyframe{};
  keyframe.id = make_id(kFrontendTag, 5);
  keyframe.T_wc = identity();
  keyframe.camera.fx_px = keyframe.camera.fy_px = 450.0;
  keyframe.camera.baseline_m = 0.11;
  keyframe.pyramid_levels = 8;
  keyframe.scale_factor = 1.2f;
  runtime::borrow(keyframe.keypoints, keypoints);
  runtime::borrow(keyframe.descriptors, descriptors);
  runtime::borrow(keyframe.point_ids, point_ids);
  EXPECT_FALSE(check(keyframe)) << problem(check(keyframe));

  keyframe.T_wc.position_m[0] = kNaN;
  EXPECT_NE(problem(check(keyframe)).find("keyframe fe:5: T_wc.position_m[0] is nan"), std::string::npos);
  keyframe.T_wc = identity();
  keypoints[0].depth_m = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(problem(check(keyframe)).find("keypoints[0]"), std::string::npos);
  keypoints[0].depth_m = 2.f;
  keypoints[0].octave = 8;
  EXPECT_NE(problem(check(keyframe)).find("octave 8"), std::string::npos);
  keypoints[0].octave = 1;
  descriptors.resize(31);
  runtime::borrow(keyframe.descriptors, descriptors);
  EXPECT_NE(problem(check(keyframe)).find("1 keypoints but 31 descriptor bytes"), std::string::npos);
  descriptors.resize(32);
  runtime::borrow(keyframe.descriptors, descriptors);
  keyframe.pyramid_levels = 100000;
  EXPECT_NE(problem(check(keyframe)).find("pyramid_levels 100000"), std::string::npos);
  keyframe.pyramid_levels = 8;
  keyframe.id = 0;
  EXPECT_EQ(problem(check(keyframe)), "id is 0 (no keyframe)");
}

TEST(MessageChecks, MapStateMarkersPassNanStatesDoNot) {
  msg::KeyframeState state{};
  state.map_version = 4;  // a version marker (id 0): only map_version is read
  EXPECT_FALSE(check(state));
  state.id = make_id(kFrontendTag, 9);
  state.T_wc = identity();
  EXPECT_FALSE(check(state));
  state.T_wc.orientation_xyzw[2] = kNaN;
  EXPECT_NE(problem(check(state)).find("keyframe state fe:9: T_wc.orientation_xyzw[2] is nan"), std::string::npos);

  msg::MapPointState point{};
  EXPECT_FALSE(check(point));  // marker
  point.id = make_id(kMapperTag, 3);
  point.min_distance_m = 0.5f;
  point.max_distance_m = 5.f;
  EXPECT_FALSE(check(point));
  point.position_w_m[2] = kNaN;
  EXPECT_NE(problem(check(point)).find("point lm:3: position_w_m[2] is nan"), std::string::npos);
  point.position_w_m[2] = 0.0;
  point.normal_w[0] = std::numeric_limits<float>::infinity();
  EXPECT_NE(problem(check(point)).find("normal_w[0] is inf"), std::string::npos);
}

TEST(MessageChecks, CorrectionsWithNanPosesOrZeroIdsAreRefused) {
  std::vector<msg::CorrectedKeyframePose> poses{{make_id(kFrontendTag, 7), identity()}};
  msg::LoopCorrection correction{};
  correction.id = make_id(kLoopCloserTag, 11);
  correction.T_matched_loop = identity();
  correction.kind = heslam_msg_CORRECTION_LOOP;
  runtime::borrow(correction.corrected_poses, poses);
  EXPECT_FALSE(check(correction));
  poses[0].T_wc.position_m[0] = kNaN;
  EXPECT_NE(
      problem(check(correction)).find("correction lc:11: keyframe fe:7: corrected_poses.T_wc.position_m[0] is nan"),
      std::string::npos);
  poses[0] = {0, identity()};
  EXPECT_NE(problem(check(correction)).find("keyframe id 0"), std::string::npos);
  poses[0] = {make_id(kFrontendTag, 7), identity()};
  runtime::set_wire_value(correction.kind, 5);
  EXPECT_EQ(problem(check(correction)), "correction lc:11: kind 5 is not a CorrectionKind");
}

TEST(MessageChecks, CalibrationWithANanFieldIsRefused) {
  msg::StereoCalibration calibration{};
  calibration.left.fx_px = calibration.right.fx_px = 450.0;
  EXPECT_FALSE(check(calibration));
  calibration.right.cy_px = kNaN;
  EXPECT_EQ(problem(check(calibration)), "right.cy_px is nan, expected a finite number");
  calibration.right.cy_px = 240.0;
  calibration.rectified.baseline_m = kInf;
  EXPECT_EQ(problem(check(calibration)), "rectified.baseline_m is inf, expected a finite number");
}

TEST(MessageChecks, FrameSizesMustMatch) {
  std::vector<std::uint8_t> image(12, 0), short_image(8, 0);
  msg::StereoFrame frame{};
  frame.width_px = 4;
  frame.height_px = 3;
  frame.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(frame.left, image);
  runtime::borrow(frame.right, image);
  EXPECT_FALSE(check(frame));
  runtime::borrow(frame.right, short_image);
  EXPECT_EQ(problem(check(frame)), "expected 12 bytes per image for 4x3x1, right has 8");
  runtime::set_wire_value(frame.encoding, 9);
  EXPECT_EQ(problem(check(frame)), "unknown encoding 9");
}

}  // namespace
}  // namespace heslam::messages
