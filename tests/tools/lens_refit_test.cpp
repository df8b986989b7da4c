// heslam-bench-lens-refit's fit on synthetic maps with a known residual radial term:
// the keypoints of a stereo camera path through a cloud of points, projected with k = 0.01 or 0,
// plus 0.3 px noise. The fit must find k and, with it, the true keyframe path length; the profile
// must rise away from the truth. This is what makes a near-zero estimate on a real map mean "the map
// does not ask for a different lens model", not "the fit cannot see one".
#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "components/core/map/map.hpp"
#include "tests/mapping/synthetic_world.hpp"
#include "tools/bench/lens_refit/lens_refit.hpp"

namespace heslam::bench {
namespace {

constexpr int kKeyframes = 8;
constexpr int kPoints = 900;
constexpr double kNoisePx = 0.3;

PinholeStereo test_camera() { return test::euroc_like_camera(); }

Pose3 true_T_wc(int i) {
  Pose3 T_wc = Pose3::Identity();
  T_wc.linear() = (Eigen::AngleAxisd(0.08 * std::sin(i), Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(0.05 * std::cos(1.3 * i), Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  T_wc.translation() = Eigen::Vector3d(0.12 * i, 0.04 * std::sin(i), 0.06 * std::cos(i));
  return T_wc;
}

// The camera of lens_refit.hpp: observed = centre + f x (1 + k r^2), per camera of the pair.
Eigen::Vector2d distorted(const PinholeStereo& camera, double x, double y, double k) {
  const double s = 1.0 + k * (x * x + y * y);
  return {camera.fx_px * x * s + camera.cx_px, camera.fy_px * y * s + camera.cy_px};
}

struct SyntheticMap {
  Map map;
  double true_path_m = 0.0;
};

SyntheticMap make_map(double radial_k) {
  const PinholeStereo camera = test_camera();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> across(-4.0, 5.0), up(-2.5, 2.5), depth(2.0, 9.0);
  std::normal_distribution<double> noise(0.0, kNoisePx), point_noise(0.0, 0.02);
  SyntheticMap synthetic;
  for (int i = 0; i < kKeyframes; ++i) {
    Keyframe keyframe;
    keyframe.id = static_cast<KeyframeId>(i + 1);
    keyframe.stamp_ns = i * 50'000'000LL;
    keyframe.T_wc = true_T_wc(i);
    synthetic.map.keyframes[keyframe.id] = keyframe;
    if (i > 0) synthetic.true_path_m += (true_T_wc(i).translation() - true_T_wc(i - 1).translation()).norm();
  }
  for (int p = 0; p < kPoints; ++p) {
    const Eigen::Vector3d p_w(across(rng), up(rng), depth(rng));
    MapPoint point;
    point.id = static_cast<PointId>(p + 1);
    point.p_w = p_w + Eigen::Vector3d(point_noise(rng), point_noise(rng), point_noise(rng));
    for (auto& [id, keyframe] : synthetic.map.keyframes) {
      const Eigen::Vector3d p_c = keyframe.T_wc.inverse() * p_w;
      if (p_c.z() < 0.5) continue;
      const double x = p_c.x() / p_c.z(), y = p_c.y() / p_c.z();
      const Eigen::Vector2d left = distorted(camera, x, y, radial_k);
      const Eigen::Vector2d right = distorted(camera, x - camera.baseline_m / p_c.z(), y, radial_k);
      if (!camera.in_image(left.x(), left.y())) continue;
      StereoFeatures& features = keyframe.features;
      Keypoint keypoint;
      keypoint.u_px = static_cast<float>(left.x() + noise(rng));
      keypoint.v_px = static_cast<float>(left.y() + noise(rng));
      features.keypoints.push_back(keypoint);
      features.descriptors.push_back(Descriptor{});
      const bool stereo = camera.in_image(right.x(), right.y());
      features.u_right_px.push_back(stereo ? static_cast<float>(right.x() + noise(rng)) : kNoStereo);
      features.depth_m.push_back(stereo ? static_cast<float>(p_c.z()) : kNoStereo);
      keyframe.point_ids.push_back(point.id);
      point.observations.emplace_back(id, static_cast<int>(features.size()) - 1);
    }
    synthetic.map.points[point.id] = point;
  }
  return synthetic;
}

TEST(LensRefit, FindsAKnownResidualRadialTermAndTheTruePathLength) {
  const SyntheticMap synthetic = make_map(0.01);
  const LensRefitResult fit = refit_residual_radial(synthetic.map, test_camera(), LensRefitOptions{});
  EXPECT_EQ(fit.keyframes, kKeyframes);
  EXPECT_GT(fit.points, kPoints / 2);
  EXPECT_GT(fit.stereo_observations, fit.observations / 2);
  EXPECT_EQ(fit.skipped_observations, 0);
  EXPECT_NEAR(fit.radial_k, 0.01, 0.0015);
  EXPECT_GT(fit.radial_k_sigma, 0.0);
  EXPECT_LT(fit.radial_k_sigma, 0.0015);
  EXPECT_LT(fit.cost_free, fit.cost_at_zero);
  // With k the path is the true one; held at 0 it is not.
  EXPECT_NEAR(fit.path_m_free / synthetic.true_path_m, 1.0, 0.002);
  EXPECT_GT(std::abs(fit.path_m_at_zero / synthetic.true_path_m - 1.0),
            std::abs(fit.path_m_free / synthetic.true_path_m - 1.0));
}

TEST(LensRefit, FindsNoTermWhereThereIsNone) {
  const SyntheticMap synthetic = make_map(0.0);
  const LensRefitResult fit = refit_residual_radial(synthetic.map, test_camera(), LensRefitOptions{});
  EXPECT_NEAR(fit.radial_k, 0.0, 0.0015);
  EXPECT_NEAR(fit.path_m_free / synthetic.true_path_m, 1.0, 0.002);

  const auto profile = refit_profile(synthetic.map, test_camera(), LensRefitOptions{}, {-0.01, 0.0, 0.01});
  ASSERT_EQ(profile.size(), 3u);
  EXPECT_GT(profile[0].cost, profile[1].cost);
  EXPECT_GT(profile[2].cost, profile[1].cost);
}

TEST(LensRefit, AWindowKeepsItsKeyframesAndRefusesFewerThanTwo) {
  const SyntheticMap synthetic = make_map(0.01);
  LensRefitOptions half;
  half.last_fraction = 0.5;
  EXPECT_EQ(refit_residual_radial(synthetic.map, test_camera(), half).keyframes, kKeyframes / 2);
  LensRefitOptions one;
  one.first_fraction = 0.0;
  one.last_fraction = 1.0 / kKeyframes;
  EXPECT_THROW(refit_residual_radial(synthetic.map, test_camera(), one), std::invalid_argument);
}

TEST(LensRefit, CountsObservationsOfMissingKeypointsAsSkipped) {
  SyntheticMap synthetic = make_map(0.0);
  synthetic.map.points.begin()->second.observations.emplace_back(1, 1'000'000);
  const LensRefitResult fit = refit_residual_radial(synthetic.map, test_camera(), LensRefitOptions{});
  EXPECT_EQ(fit.skipped_observations, 1);
}

}  // namespace
}  // namespace heslam::bench
