// The 2D view (see frame_view_renderer.hpp).
#include "tools/viewer/frame_view_renderer.hpp"

#include <cstdio>
#include <string>

#include <opencv2/imgproc.hpp>

#include "tools/viewer/colours.hpp"

namespace heslam::viewer {
namespace {

// Canvas before the first frame (EuRoC's size, so a window does not jump when frames start).
const cv::Size kEmptyImage(752, 480);
constexpr int kFlashPx = 6;
constexpr int kFeatureRadiusPx = 3;
constexpr int kCrossPx = 3;

void put(cv::Mat& image, const std::string& text, cv::Point at, const cv::Scalar& colour, double scale = 0.5) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

}  // namespace

cv::Mat FrameViewRenderer::render(const Scene& scene) {
  const cv::Size image_size = scene.has_frame ? scene.raw_left.size() : kEmptyImage;
  cv::Mat canvas(image_size.height + kStatusBarPx, 2 * image_size.width, CV_8UC3, colours::kBackground);
  if (!scene.has_frame) {
    put(canvas, "waiting for frames on camera/stereo ...", {20, image_size.height / 2}, colours::kText, 0.7);
    return canvas;
  }
  cv::Mat raw_bgr;
  cv::cvtColor(scene.raw_left, raw_bgr, cv::COLOR_GRAY2BGR);
  raw_bgr.copyTo(canvas(cv::Rect(0, 0, image_size.width, image_size.height)));

  // What the frontend extracts from: rectified (when the calibration is known) and equalized. The
  // left image is equalized on its own here; the frontend maps the pair jointly (nearly the same).
  // `rectified` must not share raw_left's pixels: remap would write into the published image.
  cv::Mat rectified;
  if (scene.rectifier && scene.rectifier->raw_size() == scene.raw_left.size()) {
    cv::Mat unused_right;
    scene.rectifier->rectify(scene.raw_left, scene.raw_left, rectified, unused_right);
  } else {
    rectified = scene.raw_left;
  }
  cv::Mat equalized, equalized_right;
  equalizer_.equalize(rectified, rectified, equalized, equalized_right);
  cv::Mat equalized_bgr;
  cv::cvtColor(equalized, equalized_bgr, cv::COLOR_GRAY2BGR);
  const cv::Rect right_half(image_size.width, 0, std::min(equalized_bgr.cols, image_size.width),
                            std::min(equalized_bgr.rows, image_size.height));
  equalized_bgr(cv::Rect(0, 0, right_half.width, right_half.height)).copyTo(canvas(right_half));

  // Drawn into the right half's own view, so a marker at its left edge cannot spill onto the raw half.
  cv::Mat right = canvas(right_half);
  int map_matches = 0, stereo_only = 0, projected = 0;
  for (const SceneFeature& feature : scene.features) {
    const cv::Point p(static_cast<int>(feature.uv_px.x), static_cast<int>(feature.uv_px.y));
    if (p.x < 0 || p.y < 0 || p.x >= right.cols || p.y >= right.rows) continue;
    switch (feature.kind) {
      case SceneFeature::Kind::kMapMatch:
        cv::circle(right, p, kFeatureRadiusPx, colours::kMapMatch, 1, cv::LINE_8);
        ++map_matches;
        break;
      case SceneFeature::Kind::kStereoOnly:
        cv::circle(right, p, kFeatureRadiusPx, colours::kStereoOnly, 1, cv::LINE_8);
        ++stereo_only;
        break;
      case SceneFeature::Kind::kProjectedMapPoint:
        cv::drawMarker(right, p, colours::kMapMatch, cv::MARKER_CROSS, 2 * kCrossPx, 1, cv::LINE_8);
        ++projected;
        break;
    }
  }

  if (scene.loop_flash) {
    cv::Mat flashed = canvas(cv::Rect(image_size.width, 0, image_size.width, canvas.rows));  // never over the raw half
    cv::rectangle(flashed, cv::Rect(0, 0, flashed.cols, flashed.rows), colours::kLoopFlash, 2 * kFlashPx);
  }

  char line[256];
  std::snprintf(line, sizeof(line),
                "frame %llu  %s  %.1f ms  tracked %u  |  %zu keyframes  %zu points  %llu loop corrections",
                static_cast<unsigned long long>(scene.frame_seq), to_string(scene.status), scene.frame_time_ms,
                scene.tracked_points, scene.map_keyframes, scene.map_points,
                static_cast<unsigned long long>(scene.loop_corrections));
  const cv::Scalar status_colour = scene.status == TrackingStatus::kLost ? colours::kRecentPoint : colours::kText;
  put(canvas, line, {8, image_size.height + 20}, status_colour);
  if (scene.frame_is_keyframe) {
    std::snprintf(line, sizeof(line), "keyframe: %d map point matches (green), %d stereo only (blue)", map_matches,
                  stereo_only);
  } else {
    std::snprintf(line, sizeof(line), "%d local map points projected at the tracked pose (green +)", projected);
  }
  put(canvas, std::string("left: raw  |  right: rectified + equalized, ") + line, {8, image_size.height + 44},
      colours::kText, 0.45);
  if (scene.loop_flash) put(canvas, "LOOP CLOSED", {image_size.width + 20, 36}, colours::kLoopFlash, 1.0);
  return canvas;
}

}  // namespace heslam::viewer
