// Known-answer geometry: rendered marker corners sit where the ground-truth poses project them, the
// stereo disparity equals f*b/z, and distorted rendering matches OpenCV's radtan projection.
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "synth_test_util.hpp"
#include "tools/dataset/ground_truth.hpp"
#include "tools/eval/trajectory_io.hpp"
#include "tools/synth/camera_rays.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace heslam::synth {
namespace {

using test::locate_corner;

constexpr double kMarginPx = 12.0;
// cornerSubPix itself is biased by up to ~0.1 px on sampled corners (pixel locking), so absolute
// locations get that much slack; disparity is measured by patch alignment, which has no such bias.
constexpr double kCornerDetectorTolerancePx = 0.15;

// Horizontal shift aligning the right image to a left patch centred on an integer pixel (1-D
// Gauss-Newton on bilinear samples): the stereo matcher's view of disparity.
double patch_disparity(const cv::Mat& left, const cv::Mat& right, cv::Point center, double guess) {
  const cv::Size size(15, 15);
  cv::Mat ref;
  cv::getRectSubPix(left, size, cv::Point2f(static_cast<float>(center.x), static_cast<float>(center.y)), ref, CV_32F);
  double d = guess;
  for (int it = 0; it < 30; ++it) {
    auto sample = [&](double disparity) {
      cv::Mat p;
      cv::getRectSubPix(right, size,
                        cv::Point2f(static_cast<float>(center.x - disparity), static_cast<float>(center.y)), p, CV_32F);
      return p;
    };
    const cv::Mat r = sample(d) - ref;
    const cv::Mat J = (sample(d + 0.25) - sample(d - 0.25)) * 2.0;
    const double step = J.dot(r) / std::max(J.dot(J), 1e-9);
    d -= step;
    if (std::abs(step) < 1e-5) break;
  }
  return d;
}

struct CornerErrors {
  int count = 0;
  double max_left_px = 0, max_right_px = 0, max_disparity_px = 0;
};

CornerErrors measure(SequenceRenderer& renderer, int frame_index) {
  const SynthFrame f = renderer.render_frame(frame_index);
  cv::Mat radiance, depth;
  renderer.render_radiance_left(frame_index, radiance, &depth);
  const PinholeStereo cam = renderer.pinhole_stereo();
  const Pose3 T_cw = f.T_wc_left.inverse();
  CornerErrors e;
  for (const MarkerCorner& m : renderer.scene().marker_corners) {
    const Eigen::Vector3d p_c = T_cw * m.p_w;
    if (p_c.z() < 0.3) continue;
    const Eigen::Vector2d uv = cam.project(p_c);
    const double ur = cam.u_right(p_c);
    if (uv.x() < kMarginPx || uv.y() < kMarginPx || uv.x() > cam.width_px - kMarginPx ||
        uv.y() > cam.height_px - kMarginPx || ur < kMarginPx)
      continue;
    // Occluded corners (another surface in front) are not visible features.
    const float z_rendered =
        depth.at<float>(static_cast<int>(std::lround(uv.y())), static_cast<int>(std::lround(uv.x())));
    if (std::abs(z_rendered - p_c.z()) > 0.02) continue;
    const cv::Point2f guess_l(static_cast<float>(uv.x() + 0.7), static_cast<float>(uv.y() - 0.6));
    const cv::Point2f guess_r(static_cast<float>(ur - 0.6), static_cast<float>(uv.y() + 0.7));
    const cv::Point2f l = locate_corner(f.left, guess_l);
    const cv::Point2f r = locate_corner(f.right, guess_r);
    e.max_left_px = std::max(e.max_left_px, std::hypot(l.x - uv.x(), l.y - uv.y()));
    e.max_right_px = std::max(e.max_right_px, std::hypot(r.x - ur, r.y - uv.y()));
    // Disparity at the integer pixel nearest the corner, against f*b/z of the surface seen there.
    const cv::Point px(static_cast<int>(std::lround(uv.x())), static_cast<int>(std::lround(uv.y())));
    const Eigen::Vector3d p_px = cam.unproject(px.x, px.y, depth.at<float>(px.y, px.x));
    const double disparity = patch_disparity(f.left, f.right, px, l.x - r.x);
    e.max_disparity_px = std::max(e.max_disparity_px, std::abs(disparity - cam.bf() / p_px.z()));
    ++e.count;
  }
  return e;
}

TEST(SynthGeometry, DisparityOfMarkerCornersIsFocalTimesBaselineOverDepth) {
  SequenceRenderer renderer(test::test_preset("marker_wall.yaml"), {.seed = 3, .frames = 40});
  int total = 0;
  for (int frame : {5, 20, 35}) {
    const CornerErrors e = measure(renderer, frame);
    total += e.count;
    std::cout << "frame " << frame << ": " << e.count << " corners, max |disparity - f*b/z| " << e.max_disparity_px
              << " px, max corner offset left " << e.max_left_px << " right " << e.max_right_px << " px\n";
    EXPECT_LT(e.max_disparity_px, 0.1) << "frame " << frame;
    EXPECT_LT(e.max_left_px, kCornerDetectorTolerancePx) << "frame " << frame;
    EXPECT_LT(e.max_right_px, kCornerDetectorTolerancePx) << "frame " << frame;
  }
  EXPECT_GT(total, 60) << "too few marker corners visible to test anything";
}

TEST(SynthGeometry, DistortedRenderingMatchesOpenCvProjection) {
  Preset preset = test::test_preset("marker_wall.yaml");
  preset.camera.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};  // EuRoC cam0
  SequenceRenderer renderer(preset, {.seed = 3, .frames = 40});
  ASSERT_TRUE(renderer.distortion_applied());
  const SynthFrame f = renderer.render_frame(20);
  const CameraSpec& c = preset.camera;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(1, 4) << c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3]);
  const Pose3 T_cw = f.T_wc_left.inverse();
  std::vector<cv::Point3d> pts;
  for (const MarkerCorner& m : renderer.scene().marker_corners) {
    const Eigen::Vector3d p = T_cw * m.p_w;
    if (p.z() > 0.3 && std::abs(p.x() / p.z()) < 0.6 && std::abs(p.y() / p.z()) < 0.4)
      pts.push_back({p.x(), p.y(), p.z()});
  }
  ASSERT_GT(pts.size(), 30u);
  std::vector<cv::Point2d> projected;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, projected);
  double max_err = 0;
  int count = 0;
  for (const auto& uv : projected) {
    if (uv.x < kMarginPx || uv.y < kMarginPx || uv.x > c.width_px - kMarginPx || uv.y > c.height_px - kMarginPx)
      continue;
    const cv::Point2f found =
        locate_corner(f.left, cv::Point2f(static_cast<float>(uv.x + 0.5), static_cast<float>(uv.y - 0.5)));
    max_err = std::max(max_err, std::hypot(found.x - uv.x, found.y - uv.y));
    ++count;
  }
  EXPECT_GT(count, 30);
  EXPECT_LT(max_err, kCornerDetectorTolerancePx);
}

TEST(SynthGeometry, UndistortInvertsDistort) {
  const std::vector<double> k = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  for (double x = -0.8; x <= 0.8; x += 0.2) {
    for (double y = -0.5; y <= 0.5; y += 0.25) {
      const Eigen::Vector2d p(x, y);
      EXPECT_LT((undistort_radtan(distort_radtan(p, k), k) - p).norm(), 1e-10);
    }
  }
}

TEST(SynthGeometry, EurocGroundTruthFilesReprojectMarkerCornersOntoTheImages) {
  // Through the files only: ground truth csv + sensor.yaml (T_BS, intrinsics, distortion) + PNGs.
  const auto dir = std::filesystem::temp_directory_path() / "heslam_synth_gt_test";
  std::filesystem::remove_all(dir);
  Preset preset = test::repo_preset("room");
  preset.photometry.noise = false;
  SequenceRenderer renderer(preset, {.seed = 11, .frames = 3});
  write_sequence(renderer, OutputFormat::kEuroc, dir);
  // The project's own readers of these files (heslam_eval, tools/dataset), as every tool uses them.
  const eval::Trajectory truth = eval::read_trajectory(euroc_ground_truth_file(dir / "mav0"));
  int checked = 0;
  double max_err = 0;
  for (int cam = 0; cam < 2; ++cam) {
    const auto cam_dir = dir / "mav0" / ("cam" + std::to_string(cam));
    cv::FileStorage fs((cam_dir / "sensor.yaml").string(), cv::FileStorage::READ);
    std::vector<double> intr, dist;
    fs["intrinsics"] >> intr;
    fs["distortion_coefficients"] >> dist;
    const cv::Mat K = (cv::Mat_<double>(3, 3) << intr[0], 0, intr[2], 0, intr[1], intr[3], 0, 0, 1);
    const Pose3 T_BS = eval::read_euroc_extrinsic(cam_dir / "sensor.yaml");
    for (int i = 0; i < 3; ++i) {
      const std::int64_t stamp = renderer.stamp_ns(i);
      const cv::Mat image =
          cv::imread((cam_dir / "data" / (std::to_string(stamp) + ".png")).string(), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(image.empty());
      const std::optional<Pose3> T_wb = poses_at_stamps(truth, {stamp}, /*max_gap_s=*/0.0).front();
      ASSERT_TRUE(T_wb.has_value()) << "stamp " << stamp << " not in the ground truth";
      const Pose3 T_cw = (*T_wb * T_BS).inverse();
      for (const MarkerCorner& m : renderer.scene().marker_corners) {
        const Eigen::Vector3d p = T_cw * m.p_w;
        if (p.z() < 0.5 || std::abs(p.x() / p.z()) > 0.6 || std::abs(p.y() / p.z()) > 0.4) continue;
        std::vector<cv::Point2d> uv;
        cv::projectPoints(std::vector<cv::Point3d>{{p.x(), p.y(), p.z()}}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K,
                          dist, uv);
        if (uv[0].x < kMarginPx || uv[0].y < kMarginPx || uv[0].x > image.cols - kMarginPx ||
            uv[0].y > image.rows - kMarginPx)
          continue;
        const cv::Point2f found =
            locate_corner(image, cv::Point2f(static_cast<float>(uv[0].x - 0.5), static_cast<float>(uv[0].y + 0.5)));
        max_err = std::max(max_err, std::hypot(found.x - uv[0].x, found.y - uv[0].y));
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 20) << "the room's first frames should see a marker";
  EXPECT_LT(max_err, kCornerDetectorTolerancePx);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace heslam::synth
