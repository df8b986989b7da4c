// Load shedding of a real-time frontend (components/frontend/load_shedding.hpp): the options and their
// refusals, the shedding rule, and the prediction over a gap on motions with a known answer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "components/frontend/frontend_options.hpp"
#include "components/frontend/load_shedding.hpp"
#include "runtime/config.hpp"

namespace heslam::frontend {
namespace {

Pose3 pose(double yaw_rad, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = t;
  return T;
}

void expect_near(const Pose3& a, const Pose3& b) {
  // Element by element: Eigen's vectorized maxCoeff trips GCC 12's -Wuninitialized with AVX-512.
  double worst = 0.0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  }
  EXPECT_LT(worst, 1e-12) << a.matrix() << "\n" << b.matrix();
}

TEST(LoadShedding, OffByDefaultAndReadFromTheRealtimeSection) {
  const FrontendOptions defaults = FrontendOptions::from_config(runtime::Config::empty());
  EXPECT_EQ(defaults.shedding.shed_after_ms, 0.0);
  EXPECT_FALSE(defaults.shedding.predict_over_gaps);
  EXPECT_EQ(defaults.shedding.frame_delay_ms, 0.0);
  const FrontendOptions on = FrontendOptions::from_config(runtime::Config::parse(
      "realtime:\n  shed_frames_after_ms: 100\n  predict_over_gaps: true\ndebug:\n  frame_delay_ms: 120\n",
      "frontend.yaml"));
  EXPECT_EQ(on.shedding.shed_after_ms, 100.0);
  EXPECT_TRUE(on.shedding.predict_over_gaps);
  EXPECT_EQ(on.shedding.frame_delay_ms, 120.0);
}

TEST(LoadShedding, BadFieldsAndSheddingInLockstepAreOneLine) {
  const auto message = [](const std::string& yaml) {
    try {
      FrontendOptions::from_config(runtime::Config::parse(yaml, "frontend.yaml"));
    } catch (const std::runtime_error& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("realtime:\n  shed_frames_after_ms: -1\n").find("realtime.shed_frames_after_ms"),
            std::string::npos);
  EXPECT_NE(message("debug:\n  frame_delay_ms: -5\n").find("debug.frame_delay_ms"), std::string::npos);
  const std::string lockstep =
      message("mapper:\n  enabled: true\nlockstep:\n  wait_for_mapper: true\nrealtime:\n  shed_frames_after_ms: 100\n");
  EXPECT_NE(lockstep.find("realtime.shed_frames_after_ms"), std::string::npos) << lockstep;
  EXPECT_NE(lockstep.find("lockstep"), std::string::npos) << lockstep;
  EXPECT_EQ(lockstep.find('\n'), std::string::npos) << lockstep;
}

TEST(LoadShedding, OnlyAStaleFrameWithANewerOneWaitingIsShed) {
  LoadSheddingOptions options;
  EXPECT_FALSE(shed_frame(options, 1000.0, true));  // off
  options.shed_after_ms = 100.0;
  EXPECT_TRUE(shed_frame(options, 100.0, true));
  EXPECT_FALSE(shed_frame(options, 99.0, true));     // late, but not stale: tracked
  EXPECT_FALSE(shed_frame(options, 1000.0, false));  // the newest frame is always tracked
}

TEST(LoadShedding, ScaledMotionIsTheConstantVelocityOverTheGap) {
  const Pose3 motion = pose(0.02, {0.01, -0.002, 0.03});
  expect_near(scale_motion(motion, 1.0), motion);
  expect_near(scale_motion(motion, 2.0), pose(0.04, {0.02, -0.004, 0.06}));
  expect_near(scale_motion(motion, 0.5), pose(0.01, {0.005, -0.001, 0.015}));
  expect_near(scale_motion(Pose3::Identity(), 3.0), Pose3::Identity());
}

TEST(LoadShedding, PredictionOnlyWhereTheGapDiffersFromTheLastMotions) {
  GapPrediction prediction;
  const Pose3 step = pose(0.01, {0.02, 0.0, 0.01});
  Pose3 T_wc = pose(0.3, {1.0, 2.0, 3.0});
  prediction.record(10, true, T_wc);
  EXPECT_FALSE(prediction.predict(12, T_wc));  // one pose: no motion known
  T_wc = T_wc * step;
  prediction.record(11, true, T_wc);
  EXPECT_FALSE(prediction.predict(12, T_wc));                            // no gap: the tracker's own motion model
  const std::optional<Pose3> over_three = prediction.predict(14, T_wc);  // frames 12 and 13 missed
  ASSERT_TRUE(over_three);
  expect_near(*over_three, T_wc * scale_motion(step, 3.0));
  // The frame after the gap: its motion spans 3 frames, the next one is 1 frame on.
  const Pose3 after_gap = T_wc * scale_motion(step, 3.0);
  prediction.record(14, true, after_gap);
  const std::optional<Pose3> next = prediction.predict(15, after_gap);
  ASSERT_TRUE(next);
  expect_near(*next, after_gap * step);
  // An untracked frame: no motion until two tracked frames follow each other again.
  prediction.record(15, false, Pose3::Identity());
  EXPECT_FALSE(prediction.predict(17, after_gap));
  prediction.record(17, true, after_gap);
  EXPECT_FALSE(prediction.predict(19, after_gap));
}

}  // namespace
}  // namespace heslam::frontend
