// Whether the estimate and the ground truth hold poses of the same frame, with the fix in the message.
#include "tools/eval/app/frame_check.hpp"

namespace heslam::eval::app {

namespace {

std::optional<PoseFrame> ground_truth_frame(const CliOptions& options, const Trajectory& gt) {
  if (gt.frame) return gt.frame;
  const Format format = options.gt_read.format ? *options.gt_read.format : detect_format(options.gt_path);
  if (format != Format::euroc) return std::nullopt;
  return options.gt_read.extrinsic_path.empty() ? PoseFrame::body : PoseFrame::cam0;
}

}  // namespace

FrameCheck check_frames(const CliOptions& options, const Trajectory& gt, const Trajectory& est) {
  FrameCheck check;
  const std::optional<PoseFrame> gt_frame = ground_truth_frame(options, gt);
  if (!est.frame || !gt_frame || *est.frame == *gt_frame) return check;
  const std::string est_name = options.est_path.string();
  const std::string est_says =
      est_name + " holds poses of the " + pose_frame_name(*est.frame) + " frame (its '# heslam frame:' header)";
  const std::string gt_is = std::string(", the ground truth of the ") + pose_frame_name(*gt_frame) + " frame";
  if (*est.frame == PoseFrame::rectified && *gt_frame == PoseFrame::cam0) {
    check.warning = est_says + gt_is + ": rotation errors include the rectifying rotation (1-2 deg on EuRoC); " +
                    "record with heslam-recorder --frame body (the default) or cam0";
  } else if (*est.frame == PoseFrame::body) {
    check.error = est_says + gt_is +
                  (options.gt_read.extrinsic_path.empty() ? std::string(": give a body-frame ground truth")
                                                          : std::string(" (--extrinsic): drop --extrinsic"));
  } else {
    check.error = est_says + gt_is +
                  (*gt_frame == PoseFrame::body
                       ? std::string(": add --extrinsic mav0/cam0/sensor.yaml (EuRoC), or record with "
                                     "heslam-recorder --frame body (the default)")
                       : std::string(": record with heslam-recorder --frame ") + pose_frame_name(*gt_frame));
  }
  return check;
}

}  // namespace heslam::eval::app
