// The recorder's inertial outputs (issue 34): the gravity-aligned world its files are written in, the
// velocities (turned with their frame's pose by a correction), and the journal carrying both.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include <Eigen/Geometry>

#include "tools/recorder/frame_journal.hpp"
#include "tools/recorder/trajectory_recorder.hpp"

namespace heslam::recorder {
namespace {

RecordedFrame tracked(std::uint64_t seq, KeyframeId reference, const Pose3& T_ref_c, const Pose3& T_wc) {
  RecordedFrame frame;
  frame.seq = seq;
  frame.stamp_ns = 1'000'000'000 + static_cast<std::int64_t>(seq) * 50'000'000;
  frame.tracked = true;
  frame.state = "OK";
  frame.reference = reference;
  frame.T_ref_c = T_ref_c;
  frame.T_wc = T_wc;
  return frame;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

TEST(InertialRecorder, GravityAlignmentTurnsGravityDownWithoutTurningAboutTheVertical) {
  // A camera world: gravity mostly along +y (down in the image), tilted.
  const Eigen::Vector3d g_w(0.8, 9.7, -1.1);
  const Eigen::Matrix3d R_gw = gravity_alignment(g_w);
  EXPECT_LT((R_gw * g_w - Eigen::Vector3d(0, 0, -g_w.norm())).norm(), 1e-12);
  EXPECT_LT((R_gw * R_gw.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  // The smallest such rotation: its axis is horizontal in both worlds (no yaw added).
  const Eigen::AngleAxisd axis_angle(R_gw);
  EXPECT_LT(std::abs(axis_angle.axis().dot(g_w.normalized())), 1e-9);
  EXPECT_LT(angle_deg(R_gw * Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ()),
            angle_deg(-g_w, Eigen::Vector3d::UnitZ()) + 1e-9);
  // Already aligned: the identity.
  EXPECT_LT((gravity_alignment(Eigen::Vector3d(0, 0, -9.81)) - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_THROW(gravity_alignment(Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_THROW(gravity_alignment(Eigen::Vector3d(NAN, 0, -9.8)), std::invalid_argument);
}

TEST(InertialRecorder, WithGravityPosesAndVelocitiesAreWrittenInTheGravityAlignedWorld) {
  TrajectoryRecorder recorder;
  Pose3 T_wk = Pose3::Identity();
  recorder.add_keyframe(1, 1'000'000'000, 0, T_wk);
  Pose3 T_wc = Pose3::Identity();
  T_wc.translation() = Eigen::Vector3d(0.2, -0.1, 0.5);
  RecordedFrame first = tracked(0, 1, T_wc, T_wc);
  first.v_w = Eigen::Vector3d(0.3, 0.0, 0.1);
  RecordedFrame second = tracked(1, 1, T_wc, T_wc);
  second.v_w = Eigen::Vector3d(0.1, 0.2, 0.0);
  second.g_w = Eigen::Vector3d(0.0, 9.81, 0.0);  // the newest gravity is the one used
  first.g_w = Eigen::Vector3d(0.0, 0.0, -9.81);
  recorder.add_frame(first);
  recorder.add_frame(second);
  RecordedTrajectories out = recorder.build();
  ASSERT_EQ(out.velocities.size(), 2u);
  ASSERT_TRUE(out.gravity_w);
  align_to_gravity(out);
  ASSERT_TRUE(out.R_gw);
  // y (gravity's direction) becomes -z: the rotation by -90 deg about x.
  const Eigen::Matrix3d expected = Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_LT((*out.R_gw - expected).norm(), 1e-12);
  EXPECT_LT((out.frames.poses_wc[0].translation() - expected * T_wc.translation()).norm(), 1e-12);
  EXPECT_LT((out.keyframes.poses_wc[0].translation()).norm(), 1e-12);  // the origin is kept
  EXPECT_LT((out.velocities[1].v_w - Eigen::Vector3d(0.1, 0.0, -0.2)).norm(), 1e-12);
  EXPECT_EQ(out.velocities[1].seq, 1u);
  EXPECT_DOUBLE_EQ(out.velocities[1].stamp_s, 1.05);
}

TEST(InertialRecorder, StereoOnlyRecordingsAreLeftAsTheyAre) {
  TrajectoryRecorder recorder;
  Pose3 T_wc = Pose3::Identity();
  T_wc.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  recorder.add_keyframe(1, 1'000'000'000, 0, Pose3::Identity());
  recorder.add_frame(tracked(0, 1, T_wc, T_wc));
  RecordedTrajectories out = recorder.build();
  align_to_gravity(out);
  EXPECT_FALSE(out.R_gw);
  EXPECT_TRUE(out.velocities.empty());
  EXPECT_EQ(out.frames.poses_wc[0].matrix(), T_wc.matrix());
}

TEST(InertialRecorder, AVelocityTurnsWithItsFramesCorrectedPose) {
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 1'000'000'000, 0, Pose3::Identity());
  RecordedFrame frame = tracked(0, 1, Pose3::Identity(), Pose3::Identity());
  frame.v_w = Eigen::Vector3d(1.0, 0.0, 0.0);
  recorder.add_frame(frame);
  Pose3 corrected = Pose3::Identity();
  corrected.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  recorder.update_keyframe(1, corrected, kNoId, false);  // a loop correction turned the keyframe by 90 deg
  const RecordedTrajectories out = recorder.build();
  ASSERT_EQ(out.velocities.size(), 1u);
  EXPECT_LT((out.velocities[0].v_w - Eigen::Vector3d(0.0, 1.0, 0.0)).norm(), 1e-12);
}

TEST(InertialRecorder, TheJournalKeepsVelocityAndGravity) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "heslam_inertial_journal_test.journal";
  std::filesystem::remove(path);
  RecordedFrame frame = tracked(1, 7, Pose3::Identity(), Pose3::Identity());
  frame.v_w = Eigen::Vector3d(0.1, -0.25, 1.0 / 3.0);
  frame.g_w = Eigen::Vector3d(0.2, 9.79, -0.4);
  {
    FrameJournal journal(path);
    journal.open_for_run("run-a");
    journal.append(frame);
    journal.append(tracked(2, 7, Pose3::Identity(), Pose3::Identity()));
  }
  FrameJournal journal(path);
  const FrameJournal::Opened opened = journal.open_for_run("run-a");
  ASSERT_EQ(opened.frames.size(), 2u);
  EXPECT_EQ(opened.torn_lines, 0);
  ASSERT_TRUE(opened.frames[0].v_w && opened.frames[0].g_w);
  EXPECT_EQ(*opened.frames[0].v_w, *frame.v_w);  // %.17g: bit for bit
  EXPECT_EQ(*opened.frames[0].g_w, *frame.g_w);
  EXPECT_FALSE(opened.frames[1].v_w);
  EXPECT_FALSE(opened.frames[1].g_w);
  journal.remove();
}

}  // namespace
}  // namespace heslam::recorder
