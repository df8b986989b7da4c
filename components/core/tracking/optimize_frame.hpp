// Motion-only BA applied to a Frame: its matched map points become the observations, the refined pose
// and the outlier flags are written back.
#pragma once

#include <cstddef>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/motion_only_ba.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

// Returns the number of inlier matches; frame.T_wc is updated only when there were observations.
int optimize_frame_pose(Frame& frame, const Map& map, const PinholeStereo& camera, const TrackerOptions& options);

// The frame's matched keypoints that are not flagged as outliers and whose map point exists, as BA
// observations; keypoint_of, when given, receives each observation's keypoint index.
std::vector<PoseObservation> frame_observations(const Frame& frame, const Map& map,
                                                std::vector<std::size_t>* keypoint_of = nullptr);

}  // namespace heslam
