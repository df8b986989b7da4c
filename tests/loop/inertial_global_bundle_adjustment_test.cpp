// The global BA with IMU factors (inertial runs, issue 34) on a synthetic room seen by a camera on a
// hand-held-like motion with exact IMU readings and a constant bias: known poses, velocities, biases.
// The IMU chain comes from an ImuBuffer as the loop closer builds it (build_global_inertial_input).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <vector>

#include "components/core/imu/imu_buffer.hpp"
#include "components/core/imu/so3.hpp"
#include "components/core/loop/global_bundle_adjustment.hpp"
#include "components/core/loop/global_inertial_chain.hpp"
#include "tests/imu/synthetic_motion.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

constexpr double kKeyframeS = 0.25;
constexpr int kKeyframes = 12;

// IMU -> camera: the camera looks along the body's x axis, 5 cm off (the mapping tests' extrinsic).
Pose3 extrinsic_T_cb() {
  Pose3 T_cb = Pose3::Identity();
  T_cb.linear() = so3::exp(Eigen::Vector3d(0.02, -1.2, 0.05));
  T_cb.translation() = Eigen::Vector3d(0.05, -0.01, 0.02);
  return T_cb;
}

struct Scene {
  test::SyntheticWorld world = test::make_room(1500, 31);
  test::Motion motion = test::ordinary_motion();
  test::SyntheticImu imu;
  Pose3 T_cb = extrinsic_T_cb();
  test::TruthMap truth;
  ImuBuffer buffer;
  std::map<KeyframeId, double> time_s;

  Pose3 true_T_wc(double t) const { return motion.pose(t) * T_cb.inverse(); }
};

// Keyframes 1..count every kKeyframeS from t = 0.5 s in the motion's world (gravity tilted); every
// reading from 0 to the last keyframe + 0.5 s in the buffer, except those in `hole` (s, open interval).
Scene make_scene(int count, double pixel_noise_px = 0.0, std::pair<double, double> hole = {-1.0, -1.0}) {
  Scene scene;
  scene.imu.bias.gyro_rad_s = Eigen::Vector3d(0.01, -0.02, 0.015);
  scene.imu.bias.accel_m_s2 = Eigen::Vector3d(0.05, 0.03, -0.04);
  for (const ImuSample& sample : scene.imu.samples(scene.motion, 0.0, 0.5 + count * kKeyframeS + 0.5)) {
    const double t = static_cast<double>(sample.stamp_ns) * 1e-9;
    if (t > hole.first && t < hole.second) continue;
    scene.buffer.add(sample);
  }
  test::ViewOptions view_options;
  view_options.pixel_noise_px = pixel_noise_px;
  view_options.clutter = 0;
  std::map<int, std::vector<std::pair<KeyframeId, int>>> seen_by;
  for (int k = 0; k < count; ++k) {
    const auto id = static_cast<KeyframeId>(k + 1);
    const double t = 0.5 + k * kKeyframeS;
    test::SyntheticView view =
        test::make_view(scene.world, id, scene.true_T_wc(t), 100 + static_cast<unsigned>(k), view_options);
    view.kf.stamp_ns = std::llround(t * 1e9);
    for (std::size_t i = 0; i < view.truth.size(); ++i) {
      if (view.truth[i] >= 0) seen_by[view.truth[i]].emplace_back(id, static_cast<int>(i));
    }
    scene.truth.true_T_wc[id] = view.kf.T_wc;
    scene.truth.map.keyframes.emplace(id, std::move(view.kf));
    scene.time_s[id] = t;
  }
  std::uint64_t counter = 0;
  for (const auto& [truth_index, observers] : seen_by) {
    if (observers.size() < 2) continue;
    MapPoint point;
    point.id = make_id(kFrontendTag, ++counter);
    point.p_w = scene.world.points_w[static_cast<std::size_t>(truth_index)];
    point.reference_kf = observers.front().first;
    scene.truth.map.points.emplace(point.id, point);
    scene.truth.true_p_w[point.id] = point.p_w;
    for (const auto& [kf_id, index] : observers) add_observation(scene.truth.map, point.id, kf_id, index);
    update_point_statistics(scene.truth.map, point.id);
  }
  for (const auto& [id, kf] : scene.truth.map.keyframes) update_connections(scene.truth.map, id, CovisibilityOptions{});
  return scene;
}

// Every keyframe but the first (the BA's gauge) moved by ~position_m / ~rotation_rad, every point by ~point_m.
void perturb(Scene& scene, double position_m, double rotation_rad, double point_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const auto draw = [&] { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  for (auto& [id, kf] : scene.truth.map.keyframes) {
    if (id == 1) continue;
    kf.T_wc.translation() += position_m * draw();
    kf.T_wc.linear() = so3::exp(rotation_rad * draw()) * kf.T_wc.linear();
  }
  for (auto& [id, point] : scene.truth.map.points) point.p_w += point_m * draw();
}

GlobalInertialInput input_of(const Scene& scene, GlobalInertialChainReport* report = nullptr) {
  return build_global_inertial_input(scene.truth.map, scene.buffer, scene.T_cb, 0, scene.imu.noise,
                                     scene.imu.gravity_w(), GlobalInertialChainOptions{}, report);
}

struct Errors {
  double position_m = 0.0, rotation_rad = 0.0, velocity_m_s = 0.0, gyro_bias = 0.0, accel_bias = 0.0;
};

Errors errors_of(const Scene& scene, const GlobalBundleAdjustmentResult& result) {
  Errors e;
  for (const auto& [id, T_wc] : result.corrected_T_wc) {
    e.position_m = std::max(e.position_m, (T_wc.translation() - scene.truth.true_T_wc.at(id).translation()).norm());
    e.rotation_rad = std::max(e.rotation_rad, test::rotation_error_rad(T_wc, scene.truth.true_T_wc.at(id)));
  }
  for (const auto& [id, state] : result.states) {
    e.velocity_m_s = std::max(e.velocity_m_s, (state.v_wb - scene.motion.velocity(scene.time_s.at(id))).norm());
    e.gyro_bias = std::max(e.gyro_bias, (state.bias.gyro_rad_s - scene.imu.bias.gyro_rad_s).norm());
    e.accel_bias = std::max(e.accel_bias, (state.bias.accel_m_s2 - scene.imu.bias.accel_m_s2).norm());
  }
  return e;
}

GlobalBundleAdjustmentOptions converging() {
  GlobalBundleAdjustmentOptions options;
  options.max_iterations = 50;  // to convergence (the loop closer's default is ORB-SLAM2's 10)
  return options;
}

TEST(LoopInertialGlobalBundleAdjustment, TheChainsFirstGuessIsCloseOnExactData) {
  const Scene scene = make_scene(kKeyframes);
  GlobalInertialChainReport report;
  const GlobalInertialInput input = input_of(scene, &report);
  ASSERT_EQ(report.intervals, kKeyframes - 1);
  EXPECT_EQ(report.not_covered, 0);
  EXPECT_TRUE(report.gyro_bias_estimated);
  ASSERT_EQ(input.states.size(), static_cast<std::size_t>(kKeyframes));
  double worst_v = 0.0;
  for (const auto& [id, state] : input.states) {
    worst_v = std::max(worst_v, (state.v_wb - scene.motion.velocity(scene.time_s.at(id))).norm());
  }
  const double gyro_error = (report.gyro_bias_rad_s - scene.imu.bias.gyro_rad_s).norm();
  std::printf("first guess on exact data: velocity %.2e m/s (accel bias ignored), gyro bias %.2e rad/s\n", worst_v,
              gyro_error);
  // The guess ignores the accelerometer bias (0.074 m/s^2 here): v is off by about |b_a| t / 2.
  EXPECT_LT(worst_v, 0.02);
  EXPECT_LT(gyro_error, 1e-4);
}

TEST(LoopInertialGlobalBundleAdjustment, ExactDataConvergesToTheTruth) {
  Scene scene = make_scene(kKeyframes);
  const GlobalInertialInput input = input_of(scene);  // from the exact poses
  perturb(scene, 0.02, 0.01, 0.02, 7);
  const GlobalBundleAdjustmentResult result =
      GlobalBundleAdjustment(converging()).compute(scene.truth.map, scene.world.camera, nullptr, &input);
  EXPECT_EQ(result.stats.imu_factors, kKeyframes - 1);
  EXPECT_EQ(result.stats.inertial_keyframes, kKeyframes);
  const Errors e = errors_of(scene, result);
  std::printf(
      "exact data: position %.2e m, rotation %.2e rad, velocity %.2e m/s, gyro bias %.2e rad/s, accel bias "
      "%.2e m/s^2 (%d iterations)\n",
      e.position_m, e.rotation_rad, e.velocity_m_s, e.gyro_bias, e.accel_bias, result.stats.iterations);
  // The floor is the 200 Hz integration's own error (the IMU factor on exact data: ~2e-6 rad, 1e-5 m per
  // 0.5 s, docs/imu.md), which the whitened IMU terms weigh against the exact pixels.
  EXPECT_LT(e.position_m, 1e-4);
  EXPECT_LT(e.rotation_rad, 5e-5);
  EXPECT_LT(e.velocity_m_s, 1e-3);
  EXPECT_LT(e.gyro_bias, 1e-4);
  EXPECT_LT(e.accel_bias, 2e-2);
}

TEST(LoopInertialGlobalBundleAdjustment, RecoversAPerturbedVelocity) {
  const Scene scene = make_scene(kKeyframes);
  GlobalInertialInput input = input_of(scene);
  const Eigen::Vector3d kick(0.10, -0.05, 0.08);
  input.states.at(6).v_wb += kick;
  const Eigen::Vector3d truth = scene.motion.velocity(scene.time_s.at(6));
  const GlobalBundleAdjustmentResult result =
      GlobalBundleAdjustment(converging()).compute(scene.truth.map, scene.world.camera, nullptr, &input);
  const double error = (result.states.at(6).v_wb - truth).norm();
  std::printf("velocity of keyframe 6 kicked by %.3f m/s: %.2e m/s from the truth after the BA\n", kick.norm(), error);
  EXPECT_LT(error, 1e-3);
  EXPECT_LT(errors_of(scene, result).position_m, 1e-4);
}

TEST(LoopInertialGlobalBundleAdjustment, TheImuPullsPosesTowardsTheTruthWhenPixelsAreNoisy) {
  // The same perturbed start and noisy pixels (1.5 px), the visual global BA against the inertial one.
  Scene scene = make_scene(kKeyframes, 1.5);
  const GlobalInertialInput input = input_of(scene);
  perturb(scene, 0.02, 0.01, 0.02, 7);
  const GlobalBundleAdjustment ba(converging());
  const Errors visual = errors_of(scene, ba.compute(scene.truth.map, scene.world.camera));
  const Errors inertial = errors_of(scene, ba.compute(scene.truth.map, scene.world.camera, nullptr, &input));
  std::printf(
      "1.5 px noise: worst keyframe position error visual %.3f mm, inertial %.3f mm; rotation %.3f / %.3f "
      "mrad\n",
      visual.position_m * 1e3, inertial.position_m * 1e3, visual.rotation_rad * 1e3, inertial.rotation_rad * 1e3);
  EXPECT_LT(inertial.position_m, visual.position_m);
}

TEST(LoopInertialGlobalBundleAdjustment, AHoleInTheReadingsBreaksTheChainThere) {
  // No reading between 1.30 and 1.40 s: the interval of keyframes 4 (1.25 s) -> 5 (1.50 s) has a 100 ms gap.
  Scene scene = make_scene(kKeyframes, 0.0, {1.30, 1.40});
  GlobalInertialChainReport report;
  const GlobalInertialInput input = input_of(scene, &report);
  EXPECT_EQ(report.intervals, kKeyframes - 2);
  EXPECT_EQ(report.not_covered, 1);
  EXPECT_NE(report.first_problem.find("keyframes 4 -> 5"), std::string::npos) << report.first_problem;
  for (const GlobalInertialInterval& interval : input.intervals) EXPECT_FALSE(interval.from == 4 && interval.to == 5);
  perturb(scene, 0.02, 0.01, 0.02, 7);
  const GlobalBundleAdjustmentResult result =
      GlobalBundleAdjustment(converging()).compute(scene.truth.map, scene.world.camera, nullptr, &input);
  EXPECT_EQ(result.stats.imu_factors, kKeyframes - 2);
  const Errors e = errors_of(scene, result);
  EXPECT_LT(e.position_m, 1e-4);
  EXPECT_LT(e.velocity_m_s, 1e-3);
}

TEST(LoopInertialGlobalBundleAdjustment, AStopFlagAbortsIt) {
  Scene scene = make_scene(kKeyframes);
  const GlobalInertialInput input = input_of(scene);
  perturb(scene, 0.02, 0.01, 0.02, 7);
  std::atomic<bool> stop{true};
  const GlobalBundleAdjustmentResult result =
      GlobalBundleAdjustment(converging()).compute(scene.truth.map, scene.world.camera, &stop, &input);
  EXPECT_TRUE(result.stats.aborted);
  EXPECT_LE(result.stats.iterations, 1);
}

TEST(LoopInertialGlobalBundleAdjustment, AnIntervalWithoutAStateIsRefused) {
  const Scene scene = make_scene(4);
  GlobalInertialInput input = input_of(scene);
  input.states.erase(3);
  EXPECT_THROW(
      {
        try {
          GlobalBundleAdjustment().compute(scene.truth.map, scene.world.camera, nullptr, &input);
        } catch (const std::invalid_argument& error) {
          EXPECT_NE(std::string(error.what()).find("keyframe 3"), std::string::npos) << error.what();
          throw;
        }
      },
      std::invalid_argument);
}

}  // namespace
}  // namespace heslam
