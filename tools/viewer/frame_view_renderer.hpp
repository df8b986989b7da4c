// The 2D view: the current raw left image and, beside it, the same image rectified and equalized as
// the frontend sees it, with the frame's features; a status bar below (tracking state, frame time,
// keyframes, points) and a flash around the right half when a loop correction arrives.
//
// The raw half is the published pixels unchanged (grey copied into all three channels), so a
// picture of this view can be compared with the dataset image.
#pragma once

#include <opencv2/core.hpp>

#include "components/core/image/histogram_equalizer.hpp"
#include "tools/viewer/scene.hpp"

namespace heslam::viewer {

class FrameViewRenderer {
 public:
  explicit FrameViewRenderer(const HistogramEqualizerOptions& equalizer) : equalizer_(equalizer) {}
  // An empty canvas with a "waiting" line before the first frame. Not thread-safe (one drawing thread).
  cv::Mat render(const Scene& scene);

  static constexpr int kStatusBarPx = 56;

 private:
  HistogramEqualizer equalizer_;
};

}  // namespace heslam::viewer
