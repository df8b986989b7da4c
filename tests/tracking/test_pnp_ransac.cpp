// PnP RANSAC: known pose from correspondences with 40 % outliers; same seed, same answer; no pose from noise.
#include <gtest/gtest.h>

#include "components/core/solve/pnp_ransac.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

std::vector<PnpCorrespondence> make_correspondences(const PinholeStereo& camera, const Pose3& T_cw, int count,
                                                    double outlier_fraction, std::uint64_t seed,
                                                    std::vector<bool>* is_outlier = nullptr) {
  std::mt19937_64 rng(seed);
  std::vector<PnpCorrespondence> out;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p_c((test::uniform01(rng) - 0.5) * 8.0, (test::uniform01(rng) - 0.5) * 6.0,
                              2.0 + 10.0 * test::uniform01(rng));
    PnpCorrespondence c;
    c.p_w = T_cw.inverse() * p_c;
    const Eigen::Vector2d uv = camera.project(p_c);
    const bool outlier = test::uniform01(rng) < outlier_fraction;
    if (outlier) {
      c.u_px = camera.width_px * test::uniform01(rng);
      c.v_px = camera.height_px * test::uniform01(rng);
    } else {
      c.u_px = uv.x() + 0.5 * test::gaussian(rng);
      c.v_px = uv.y() + 0.5 * test::gaussian(rng);
    }
    if (is_outlier) is_outlier->push_back(outlier);
    out.push_back(c);
  }
  return out;
}

Pose3 test_pose() {
  Pose3 T_cw = Pose3::Identity();
  T_cw.linear() = Eigen::AngleAxisd(1.2, Eigen::Vector3d(0.3, -1.0, 0.4).normalized()).toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(1.5, -0.7, 2.0);
  return T_cw;
}

TEST(PnpRansac, RecoversPoseWithFortyPercentOutliers) {
  const PinholeStereo camera = test::synthetic_camera();
  const Pose3 T_cw = test_pose();
  std::vector<bool> is_outlier;
  const auto correspondences = make_correspondences(camera, T_cw, 200, 0.4, 11, &is_outlier);
  const auto result = PnpRansac().compute(camera, correspondences);
  ASSERT_TRUE(result.has_value());
  EXPECT_LT((result->T_cw.translation() - T_cw.translation()).norm(), 0.02);
  EXPECT_LT(test::rotation_error_deg(result->T_cw, T_cw), 0.2);
  int wrong_inliers = 0;
  for (std::size_t i = 0; i < is_outlier.size(); ++i) wrong_inliers += (is_outlier[i] && result->inlier[i]) ? 1 : 0;
  EXPECT_LE(wrong_inliers, 2);  // a random pixel can land near its true projection by chance
  const int true_inliers = static_cast<int>(std::count(is_outlier.begin(), is_outlier.end(), false));
  EXPECT_GE(result->inliers, true_inliers * 9 / 10);
}

TEST(PnpRansac, SameSeedSamePoseBitForBit) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto correspondences = make_correspondences(camera, test_pose(), 150, 0.5, 5);
  PnpRansacOptions options;
  options.seed = 42;
  const auto a = PnpRansac(options).compute(camera, correspondences);
  const auto b = PnpRansac(options).compute(camera, correspondences);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->T_cw.matrix(), b->T_cw.matrix());
  EXPECT_EQ(a->inlier, b->inlier);
}

TEST(PnpRansac, PureNoiseGivesNoPose) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto correspondences = make_correspondences(camera, test_pose(), 100, 1.0, 9);
  PnpRansacOptions options;
  options.min_inliers = 20;
  EXPECT_FALSE(PnpRansac(options).compute(camera, correspondences).has_value());
}

TEST(PnpRansac, TooFewCorrespondencesGiveNoPose) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto correspondences = make_correspondences(camera, test_pose(), 3, 0.0, 9);
  EXPECT_FALSE(PnpRansac().compute(camera, correspondences).has_value());
}

}  // namespace
}  // namespace heslam
