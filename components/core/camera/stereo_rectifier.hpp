// Rectifies raw stereo pairs into the shared PinholeStereo model with precomputed remap tables.
//
// The rectified model comes from cv::stereoRectify with alpha 0 (only valid pixels, as ORB-SLAM2's
// EuRoC settings), or from explicit LEFT/RIGHT R/P (ORB-SLAM2 settings), or is the input model when
// the calibration says the images are already rectified (KITTI), in which case rectify() is a no-op.
// An equidistant (fisheye) pair is rectified to a pinhole pair by cv::fisheye::stereoRectify with
// balance 0 (the focal length that keeps only valid pixels along the image's edges) and
// cv::fisheye::initUndistortRectifyMap: the same CV_16SC2 tables, remapped alike.
#pragma once

#include <opencv2/core.hpp>

#include "components/core/camera/bilinear_remap.hpp"
#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/geometry/pose.hpp"

namespace heslam {

class StereoRectifier {
 public:
  // Throws std::runtime_error (one line naming the calibration source) on an unusable calibration.
  explicit StereoRectifier(const StereoCalibration& calibration);

  // The rectified model every algorithm after rectification works in.
  const PinholeStereo& camera() const { return camera_; }

  // Rectified left camera -> body frame (T_BS of cam0 composed with the rectifying rotation), for
  // comparing with ground truth given for the body.
  const Pose3& T_B_rect() const { return T_B_rect_; }

  // Raw image size the calibration expects.
  cv::Size raw_size() const { return raw_size_; }

  // Inputs: raw 8-bit images of raw_size(). Outputs are rectified images of the camera() size. With
  // already-rectified input the outputs share the inputs' pixels (no copy). Throws std::runtime_error
  // when an image has the wrong size or type.
  void rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat& left_rect, cv::Mat& right_rect) const;

  // One image of the pair, with the same pixels as rectify() (BilinearRemap: cv::remap's arithmetic
  // in a tenth of its instructions), on the calling thread only (no OpenCV pool): the two may run at
  // once on two threads (const, the maps are only read). An output that already has the camera()
  // size and type is written in place (no allocation).
  void rectify_left(const cv::Mat& left_raw, cv::Mat& left_rect) const;
  void rectify_right(const cv::Mat& right_raw, cv::Mat& right_rect) const;

 private:
  // The rectified model and remap tables for raw (not yet rectified) input; OpenCV may throw.
  void compute_rectification(const StereoCalibration& calibration);

  PinholeStereo camera_;
  Pose3 T_B_rect_ = Pose3::Identity();
  cv::Size raw_size_;
  bool passthrough_ = false;
  // cv::initUndistortRectifyMap with CV_16SC2: fixed-point maps, the fastest cv::remap path.
  cv::Mat left_map_xy_, left_map_frac_, right_map_xy_, right_map_frac_;
  BilinearRemap left_remap_, right_remap_;  // on the same maps
};

}  // namespace heslam
