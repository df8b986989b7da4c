// heslam-synth's fisheye camera (--camera fisheye: config/synth/cameras/fisheye.yaml, equidistant lenses):
// every rendered pixel looks along the ray the Kannala-Brandt model gives it (checked against OpenCV's
// cv::fisheye), the sequence's sensor.yaml and ORB-SLAM3 KannalaBrandt8 settings are read back into the
// rendering's exact lens, and a lens the renderer cannot draw is one line naming the field.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "synth_test_util.hpp"
#include "test_support.hpp"
#include "tools/synth/camera_rays.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

// The room seen through config/synth/cameras/fisheye.yaml (heslam-synth --preset room --camera fisheye).
Preset fisheye_room() {
  Preset preset = test::repo_preset("room");
  apply_camera_file(find_camera("fisheye"), preset);
  return preset;
}

TEST(SynthFisheye, EveryPixelLooksAlongItsKannalaBrandtRay) {
  const Preset preset = fisheye_room();
  const CameraSpec& c = preset.camera;
  ASSERT_EQ(c.lens, LensModel::kEquidistant);
  const CameraRays rays(c, /*apply_distortion=*/true);
  ASSERT_TRUE(rays.distorted());
  std::vector<cv::Point3d> points;
  std::vector<cv::Point2d> pixels;
  for (int r = 0; r < c.height_px; r += 7) {
    for (int col = 0; col < c.width_px; col += 7) {
      const int i = r * c.width_px + col;
      points.emplace_back(rays.x(i), rays.y(i), 1.0);
      pixels.emplace_back(col, r);
    }
  }
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
  std::vector<cv::Point2d> projected;
  cv::fisheye::projectPoints(points, projected, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, c.distortion);
  double worst_px = 0.0;
  for (std::size_t k = 0; k < pixels.size(); ++k) worst_px = std::max(worst_px, cv::norm(projected[k] - pixels[k]));
  // The table holds floats: ~1e-7 relative on rays up to tan(78 deg) = 4.6 long.
  EXPECT_LT(worst_px, 1e-3);
  // A wide lens: the corners see more than 75 degrees off the axis.
  EXPECT_GT(std::atan(std::hypot(rays.x(0), rays.y(0))) * 180.0 / M_PI, 75.0);
}

TEST(SynthFisheye, SensorYamlAndOrbSlam3SettingsCarryTheRenderedLens) {
  const fs::path dir = fs::temp_directory_path() / "heslam_synth_fisheye_output";
  fs::remove_all(dir);
  Preset preset = fisheye_room();
  preset.frames = 2;
  SequenceRenderer renderer(preset, {.seed = 3});
  write_sequence(renderer, OutputFormat::kEuroc, dir);
  const CameraSpec& c = preset.camera;
  const StereoCalibration euroc = load_euroc_calibration(dir / "mav0");
  const StereoCalibration orbslam3 = load_orbslam_settings(dir / "orbslam3_settings.yaml");
  EXPECT_FALSE(fs::exists(dir / "orbslam2_settings.yaml")) << "ORB-SLAM2 has no fisheye lens";
  for (const StereoCalibration* calibration : {&euroc, &orbslam3}) {
    for (const CameraModel* camera : {&calibration->left, &calibration->right}) {
      EXPECT_EQ(camera->distortion_model, DistortionModel::kEquidistant);
      EXPECT_EQ(camera->distortion, c.distortion);
      EXPECT_EQ(camera->fx_px, c.fx_px);
      EXPECT_EQ(camera->fy_px, c.fy_px);
      EXPECT_EQ(camera->cx_px, c.cx_px);
      EXPECT_EQ(camera->cy_px, c.cy_px);
      EXPECT_EQ(camera->width_px, c.width_px);
    }
    EXPECT_NEAR(calibration->T_rl().translation().x(), -c.baseline_m, 1e-12);
    EXPECT_LT((calibration->T_rl().linear() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  }
  // Parallel cameras: rectification keeps the baseline and turns nothing.
  const StereoRectifier rectifier(euroc);
  EXPECT_NEAR(rectifier.camera().baseline_m, c.baseline_m, 1e-12);
  EXPECT_LT(((euroc.left.T_BS.inverse() * rectifier.T_B_rect()).linear() - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  fs::remove_all(dir);
}

TEST(SynthFisheye, LensTheRendererCannotDrawIsOneLine) {
  CameraSpec c = fisheye_room().camera;
  c.fx_px = c.fy_px = 200.0;  // 752 px across at 200 px/rad: the corners see 128 deg off the axis
  try {
    const CameraRays rays(c, true);
    FAIL() << "a lens seeing behind the camera rendered";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()).find("camera: the equidistant lens sees 85"), 0u) << error.what();
  }
  const ::heslam::test::ScratchDir dir("synth_fisheye_preset");
  std::ofstream(dir.path() / "p.yaml") << "%YAML:1.0\n---\nscene: room\ncamera:\n  distortion_model: equidistant\n"
                                       << "  distortion: [0.0, 0.0, 0.0, 0.0, 0.0]\n";
  try {
    load_preset(dir.path() / "p.yaml");
    FAIL() << "5 coefficients for a fisheye taken";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()), (dir.path() / "p.yaml").string() +
                                             ": field 'camera.distortion' expected [k1, k2, k3, k4] (an equidistant "
                                             "lens has 4 coefficients)");
  }
}

}  // namespace
}  // namespace heslam::synth
