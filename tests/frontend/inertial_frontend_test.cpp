// The frontend's inertial side without DDS: a loop correction moves the recent frames it predicts from.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "components/core/imu/so3.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/tracker.hpp"
#include "components/frontend/inertial_frontend.hpp"
#include "tests/imu/synthetic_motion.hpp"

namespace heslam::frontend {
namespace {

std::int64_t ns(double t_s) { return std::llround(t_s * 1e9); }

// Two frames tracked on the hand-held motion (camera = IMU body), exact readings around them.
InertialFrontend tracked_two_frames(const test::Motion& motion) {
  InertialFrontend inertial(InertialOptions{}, "test/imu");
  ImuCalibration calibration;
  calibration.T_BS = Pose3::Identity();
  inertial.set_imu_calibration(calibration);
  inertial.set_camera(Pose3::Identity());
  const test::SyntheticImu imu;
  for (const ImuSample& sample : imu.samples(motion, 0.0, 1.0)) EXPECT_TRUE(inertial.buffer().add(sample).accepted());
  const Map map;
  for (const double t : {0.20, 0.25}) {
    TrackResult result;
    result.state = TrackingState::kOk;
    result.T_wc = motion.pose(t);
    inertial.update(ns(t), result, map);
  }
  return inertial;
}

// A correction that moved the last frame by T_corr (Frontend::follow_loop_correction): the next prediction
// is the uncorrected one moved by T_corr, i.e. in the corrected map, not in the old one.
TEST(InertialFrontend, ACorrectionMovesTheFramesItPredictsFrom) {
  const test::Motion motion = test::ordinary_motion();
  InertialFrontend plain = tracked_two_frames(motion);
  InertialFrontend corrected = tracked_two_frames(motion);
  Pose3 T_corr = Pose3::Identity();
  T_corr.linear() = so3::exp(Eigen::Vector3d(0.004, -0.003, 0.03));
  T_corr.translation() = Eigen::Vector3d(0.12, -0.05, 0.01);
  corrected.moved(T_corr);

  const InertialFrontend::Prediction before = plain.predict(ns(0.30));
  const InertialFrontend::Prediction after = corrected.predict(ns(0.30));
  ASSERT_TRUE(before.T_wc.has_value());
  ASSERT_TRUE(after.T_wc.has_value());
  const Pose3 expected = T_corr * *before.T_wc;
  EXPECT_LT((after.T_wc->translation() - expected.translation()).norm(), 1e-12);
  EXPECT_LT((after.T_wc->linear() - expected.linear()).norm(), 1e-12);
  // Without the move the prediction stays in the old map, 13 cm away.
  EXPECT_GT((before.T_wc->translation() - expected.translation()).norm(), 0.1);
}

}  // namespace
}  // namespace heslam::frontend
