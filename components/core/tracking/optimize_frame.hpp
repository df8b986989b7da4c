// Motion-only BA applied to a Frame: its matched map points become the observations, the refined pose
// and the outlier flags are written back.
#pragma once

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

// Returns the number of inlier matches; frame.T_wc is updated only when there were observations.
int optimize_frame_pose(Frame& frame, const Map& map, const PinholeStereo& camera, const TrackerOptions& options);

}  // namespace heslam
