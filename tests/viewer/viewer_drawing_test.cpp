// heslam-viewer's drawing without DDS: the top view draws one frustum per keyframe (in the colour
// only frustums use) and fits the scene; the 2D view keeps the raw image's pixels; options reject
// what cannot work; the recorder writes a video or a PNG sequence.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/camera/stereo_calibration.hpp"

#include "test_support.hpp"
#include "tools/viewer/colours.hpp"
#include "tools/viewer/frame_view_renderer.hpp"
#include "tools/viewer/top_view_renderer.hpp"
#include "tools/viewer/video_sink.hpp"
#include "tools/viewer/viewer_options.hpp"

namespace heslam::viewer {
namespace {

int pixels_of(const cv::Mat& image, const cv::Scalar& bgr) {
  cv::Mat mask;
  cv::inRange(image, bgr, bgr, mask);
  return cv::countNonZero(mask);
}

// Keyframes on a 2 m circle in the x-z plane, looking at its centre, and points on a wall.
Scene circle_scene(int keyframes) {
  Scene scene;
  scene.camera = PinholeStereo{458.0, 457.0, 367.0, 248.0, 0.11, 752, 480};
  for (int i = 0; i < keyframes; ++i) {
    const double angle = 2.0 * M_PI * i / keyframes;
    Pose3 T_wc = Pose3::Identity();
    T_wc.translation() = Eigen::Vector3d(2.0 * std::cos(angle), 0.0, 2.0 * std::sin(angle));
    T_wc.linear() = Eigen::AngleAxisd(-angle - M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
    scene.keyframes_T_wc.push_back(T_wc);
  }
  for (int i = 0; i < 200; ++i) {
    scene.points.push_back(
        {Eigen::Vector3d(-1.0 + 0.01 * i, 0.0, 3.5), i % 4 == 0 ? PointCategory::kRecent : PointCategory::kMap});
  }
  scene.map_keyframes = scene.keyframes_T_wc.size();
  scene.map_points = scene.points.size();
  return scene;
}

TEST(ViewerTopView, DrawsOneFrustumPerKeyframeInTheFrustumColourOnly) {
  const Scene scene = circle_scene(12);
  const TopView view = TopViewRenderer(cv::Size(600, 600)).render(scene, Layers{});
  EXPECT_EQ(view.frustums_drawn, 12u);
  EXPECT_EQ(view.points_drawn, 200u);
  EXPECT_GT(pixels_of(view.image, colours::kKeyframe), 12 * 10);
  EXPECT_GT(pixels_of(view.image, colours::kRecentPoint), 0);

  Layers no_keyframes;
  no_keyframes.keyframes = false;
  const TopView without = TopViewRenderer(cv::Size(600, 600)).render(scene, no_keyframes);
  EXPECT_EQ(without.frustums_drawn, 0u);
  EXPECT_EQ(pixels_of(without.image, colours::kKeyframe), 0);
}

TEST(ViewerTopView, FitsTheKeyframesInsideTheImage) {
  const Scene scene = circle_scene(8);
  const TopView view = TopViewRenderer(cv::Size(400, 400)).render(scene, Layers{});
  // Keyframe colour in every quadrant of the image: the circle is spread over the whole view.
  for (const cv::Rect quadrant : {cv::Rect(0, 0, 200, 200), cv::Rect(200, 0, 200, 200), cv::Rect(0, 200, 200, 200),
                                  cv::Rect(200, 200, 200, 200)}) {
    EXPECT_GT(pixels_of(view.image(quadrant), colours::kKeyframe), 0) << quadrant;
  }
}

// The bounding box of the pixels of one colour (empty when there are none).
cv::Rect box_of(const cv::Mat& image, const cv::Scalar& bgr) {
  cv::Mat mask;
  cv::inRange(image, bgr, bgr, mask);
  std::vector<cv::Point> pixels;
  cv::findNonZero(mask, pixels);
  return pixels.empty() ? cv::Rect() : cv::boundingRect(pixels);
}

// A 1.2 m x 0.6 m loop (the camera path of a small room) inside a map whose points spread over
// 14 m x 10 m (what made the trajectory a 30-pixel blob when the view fitted the map), with its
// ground truth 5 cm beside it.
Scene small_loop_in_a_large_map() {
  Scene scene = circle_scene(4);
  scene.keyframes_T_wc.clear();
  scene.points.clear();
  for (int i = 0; i <= 100; ++i) {
    const double angle = 2.0 * M_PI * i / 100;
    const Eigen::Vector3d p_w(0.6 * std::cos(angle), 0.0, 0.3 * std::sin(angle));
    scene.trajectory_w.push_back(p_w);
    scene.ground_truth_w.push_back(p_w + Eigen::Vector3d(0.05, 0.0, 0.0));
  }
  for (int i = 0; i < 400; ++i) {
    scene.points.push_back({Eigen::Vector3d(-7.0 + 0.035 * i, 0.0, (i % 2 == 0 ? -5.0 : 5.0)), PointCategory::kMap});
  }
  scene.map_points = scene.points.size();
  return scene;
}

TEST(ViewerTopView, FitsTheTrajectoryByDefaultAndTheMapOnRequest) {
  const Scene scene = small_loop_in_a_large_map();
  const TopView view = TopViewRenderer(kDefaultTopViewSize).render(scene, Layers{});
  // The loop is twice as wide as deep: its width spans the picture but for the margins.
  const cv::Rect trajectory = box_of(view.image, colours::kTrajectory);
  EXPECT_GE(trajectory.width, 0.85 * kDefaultTopViewSize.width) << trajectory;
  EXPECT_GE(trajectory.height, 0.4 * kDefaultTopViewSize.height) << trajectory;
  // The ground truth is drawn wider, under the estimate: it shows beside it and where they overlap.
  EXPECT_GE(box_of(view.image, colours::kGroundTruth).width, 0.85 * kDefaultTopViewSize.width);
  EXPECT_GT(pixels_of(view.image, colours::kGroundTruth), 2 * pixels_of(view.image, colours::kTrajectory) / 3);

  const TopView map = TopViewRenderer(kDefaultTopViewSize, TopViewFit::kMap).render(scene, Layers{});
  const cv::Rect small = box_of(map.image, colours::kTrajectory);
  EXPECT_GT(small.width, 0);
  EXPECT_LT(small.width, 0.15 * kDefaultTopViewSize.width) << small;
  EXPECT_EQ(map.points_drawn, 400u);
}

TEST(ViewerTopView, DrawsAGridAScaleBarOfOneGridStepAndTheAxes) {
  const Scene scene = small_loop_in_a_large_map();
  const TopView view = TopViewRenderer(kDefaultTopViewSize).render(scene, Layers{});
  // 1.2 m over ~840 px: ~670 px/m; a round step with cells of at least 60 px is 0.1 m.
  EXPECT_NEAR(view.scale_px_per_m, 840.0 / 1.25, 10.0);
  EXPECT_DOUBLE_EQ(view.grid_step_m, 0.1);
  // Grid lines across the picture: one every step (about 67 px), so at least 10 in each direction.
  cv::Mat grid;
  cv::inRange(view.image, colours::kGrid, colours::kGrid, grid);
  int vertical_lines = 0;
  const int row = kDefaultTopViewSize.height / 2;
  for (int column = 1; column < grid.cols; ++column) {
    if (grid.at<std::uint8_t>(row, column) != 0 && grid.at<std::uint8_t>(row, column - 1) == 0) ++vertical_lines;
  }
  EXPECT_GE(vertical_lines, 10);
  // The scale bar, bottom left, is one grid step long.
  const cv::Rect bar = box_of(view.image, colours::kScaleBar);
  ASSERT_GT(bar.width, 0);
  EXPECT_LT(bar.x, kDefaultTopViewSize.width / 4);
  EXPECT_GT(bar.y, kDefaultTopViewSize.height - 40);
  EXPECT_EQ(bar.width, std::lround(view.grid_step_m * view.scale_px_per_m) + 1);
  // The x / z arrows, bottom right.
  EXPECT_GT(box_of(view.image, colours::kAxisX).x, kDefaultTopViewSize.width * 3 / 4);
  EXPECT_GT(box_of(view.image, colours::kAxisZ).y, kDefaultTopViewSize.height * 3 / 4);
  // A map 1000 times larger: the step grows with it (1, 2 or 5 x 10^k).
  Scene large = scene;
  for (Eigen::Vector3d& p : large.trajectory_w) p *= 1000.0;
  large.ground_truth_w.clear();
  EXPECT_DOUBLE_EQ(TopViewRenderer(kDefaultTopViewSize).render(large, Layers{}).grid_step_m, 100.0);
}

TEST(ViewerTopView, EmptySceneGivesABlankPictureWithoutFailing) {
  const TopView view = TopViewRenderer(cv::Size(300, 300)).render(Scene{}, Layers{});
  EXPECT_EQ(view.frustums_drawn, 0u);
  EXPECT_EQ(view.image.size(), cv::Size(300, 300));
}

TEST(ViewerFrameView, RawHalfKeepsThePublishedPixelsAndFeaturesGoOnTheRightHalf) {
  Scene scene;
  scene.has_frame = true;
  scene.raw_left = cv::Mat(480, 752, CV_8UC1);
  cv::randu(scene.raw_left, 0, 256);
  scene.features.push_back({cv::Point2f(100.f, 100.f), SceneFeature::Kind::kMapMatch});
  scene.features.push_back({cv::Point2f(200.f, 100.f), SceneFeature::Kind::kStereoOnly});
  scene.features.push_back({cv::Point2f(0.f, 300.f), SceneFeature::Kind::kProjectedMapPoint});  // at the seam
  scene.frame_is_keyframe = true;
  scene.status = TrackingStatus::kTracking;
  scene.loop_flash = true;
  FrameViewRenderer renderer{HistogramEqualizerOptions{}};
  const cv::Mat view = renderer.render(scene);
  ASSERT_EQ(view.size(), cv::Size(2 * 752, 480 + FrameViewRenderer::kStatusBarPx));
  cv::Mat raw_bgr;
  cv::cvtColor(scene.raw_left, raw_bgr, cv::COLOR_GRAY2BGR);
  EXPECT_EQ(cv::norm(view(cv::Rect(0, 0, 752, 480)), raw_bgr, cv::NORM_INF), 0.0);
  const cv::Mat right = view(cv::Rect(752, 0, 752, 480));
  EXPECT_GT(pixels_of(right, colours::kMapMatch), 0);
  EXPECT_GT(pixels_of(right, colours::kStereoOnly), 0);
  EXPECT_GT(pixels_of(right, colours::kLoopFlash), 0);
}

TEST(ViewerFrameView, RectifyingForTheRightHalfLeavesTheRawImageUntouched) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const std::filesystem::path mav0 = test::shared_dataset("euroc_mh01_handheld") / "mav0";
  Scene scene;
  scene.has_frame = true;
  scene.raw_left = cv::imread((mav0 / "cam0/data/1403636584763555584.png").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(scene.raw_left.empty());
  const cv::Mat original = scene.raw_left.clone();
  scene.rectifier = std::make_shared<const StereoRectifier>(load_euroc_calibration(mav0));
  FrameViewRenderer renderer{HistogramEqualizerOptions{}};
  cv::Mat view;
  for (int i = 0; i < 3; ++i) view = renderer.render(scene);  // the drawing thread draws a frame repeatedly
  EXPECT_EQ(cv::norm(scene.raw_left, original, cv::NORM_INF), 0.0);
  cv::Mat raw_bgr;
  cv::cvtColor(original, raw_bgr, cv::COLOR_GRAY2BGR);
  EXPECT_EQ(cv::norm(view(cv::Rect(0, 0, raw_bgr.cols, raw_bgr.rows)), raw_bgr, cv::NORM_INF), 0.0);
}

TEST(ViewerOptions, ParsesFlagsAndRejectsWhatCannotWork) {
  EXPECT_EQ(ViewerOptions::parse({}).fit, TopViewFit::kTrajectory);
  EXPECT_EQ(ViewerOptions::parse({"--fit", "map"}).fit, TopViewFit::kMap);
  EXPECT_THROW(ViewerOptions::parse({"--fit", "points"}), std::runtime_error);
  const ViewerOptions o =
      ViewerOptions::parse({"--headless", "--out", "/tmp/x", "--snapshot-every", "2.5", "--rate", "10"});
  EXPECT_TRUE(o.headless);
  EXPECT_EQ(o.out_dir, "/tmp/x");
  EXPECT_DOUBLE_EQ(o.snapshot_every_s, 2.5);
  EXPECT_DOUBLE_EQ(o.draw_rate_hz, 10.0);
  EXPECT_THROW(ViewerOptions::parse({"--headless"}), std::runtime_error);
  EXPECT_THROW(ViewerOptions::parse({"--rate", "fast"}), std::runtime_error);
  EXPECT_THROW(ViewerOptions::parse({"--he-mode", "magic"}), std::runtime_error);
  EXPECT_THROW(ViewerOptions::parse({"--frobnicate"}), std::runtime_error);
  EXPECT_NE(ViewerOptions::usage().find("covisibility"), std::string::npos);
}

TEST(ViewerVideoSink, WritesAVideoOrAPngSequence) {
  const test::ScratchDir dir("viewer_video");
  VideoSink sink(dir.path() / "view.mp4", 10.0);
  cv::Mat frame(120, 160, CV_8UC3, cv::Scalar(0, 128, 255));
  for (int i = 0; i < 5; ++i) sink.write(frame);
  const std::string summary = sink.close();
  const bool video =
      std::filesystem::exists(dir.path() / "view.mp4") && std::filesystem::file_size(dir.path() / "view.mp4") > 0;
  const bool pngs = std::filesystem::exists(dir.path() / "view_000004.png");
  EXPECT_TRUE(video || pngs) << summary;
  EXPECT_NE(summary.find("5 frames"), std::string::npos) << summary;
}

}  // namespace
}  // namespace heslam::viewer
