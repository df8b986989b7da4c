// The stationary test: is the frame's motion since the last frame significant, and in which degrees
// of freedom? A still camera should be estimated still, a camera turning in place (a robot rotating
// on the spot, a MAV rocking on the ground) should keep its centre, instead of jittering by the
// per-frame measurement noise. Not in ORB-SLAM2; visual-inertial systems call the first case a
// zero-velocity update.
//
// Nested likelihood-ratio tests on the frame's inlier observations after the local map BA, each
// against the full 6-dof optimum (chi-square of the whitened reprojection errors):
//   still:    the last pose itself,                         accepted if the chi2 increase < chi2(6 dof)
//   rotating: the last camera centre, rotation re-estimated, accepted if the chi2 increase < chi2(3 dof)
//   moving:   the optimum.
// The simplest hypothesis not rejected wins. While a camera is held, the last pose is where the hold
// began, so slow motion is released as soon as it adds up to a significant difference: it never
// accumulates unseen.
#pragma once

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

enum class FrameMotion { kMoving, kRotatingInPlace, kStill };
const char* to_string(FrameMotion motion);

struct StationaryTestResult {
  FrameMotion motion = FrameMotion::kMoving;
  Pose3 T_wc = Pose3::Identity();  // the pose of the chosen hypothesis
};

// frame.T_wc is the 6-dof optimum; the frame's matches are its inliers (outliers discarded).
StationaryTestResult test_stationary(const Frame& frame, const Map& map, const PinholeStereo& camera,
                                     const TrackerOptions& options, const Pose3& T_wc_last);

}  // namespace heslam
