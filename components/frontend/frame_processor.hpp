// The frontend's per-frame chain without DDS: raw stereo pair -> rectification -> HE -> ORB ->
// stereo matching -> tracking. The frontend process wraps it; tests run it directly to check that the
// DDS run gives the same trajectory as the chain alone.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/tracking/tracker.hpp"
#include "components/frontend/frontend_options.hpp"
#include "components/messages/odometry.hpp"

namespace heslam::frontend {

struct FrameOutput {
  TrackResult result;
  std::uint32_t keypoints = 0;         // extracted in the left image
  std::uint32_t stereo_keypoints = 0;  // ... of which with a stereo match
  // rectify, he, extract, stereo, features, track_initial, track_local_map, track_keyframe, track,
  // cpu (the process's CPU time over the frame, all threads), total — in this order (odometry
  // stage_times and status stages use the same names); total is wall time and last.
  std::vector<messages::StageTiming> timings;
};

class FrameProcessor {
 public:
  // Throws std::runtime_error when the calibration cannot be rectified.
  FrameProcessor(const StereoCalibration& calibration, const FrontendOptions& options);

  // Inputs: raw 8-bit grey images of the calibration's raw size. Throws std::runtime_error naming the
  // frame when they have another size.
  FrameOutput process(std::int64_t stamp_ns, std::uint64_t seq, const cv::Mat& left_raw, const cv::Mat& right_raw);

  const StereoRectifier& rectifier() const { return rectifier_; }
  const PinholeStereo& camera() const { return rectifier_.camera(); }
  Tracker& tracker() { return tracker_; }

 private:
  StereoRectifier rectifier_;
  StereoFeaturePipeline pipeline_;
  Tracker tracker_;
  cv::Mat left_rect_, right_rect_;
};

}  // namespace heslam::frontend
