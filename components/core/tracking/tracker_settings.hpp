// The tracker's options from an ORB-SLAM2 settings file (config/camera/*.yaml), the file a user of
// ORB-SLAM edits: its standard keys with ORB-SLAM2's meaning, heslam's own under Tracker.*.
//   Camera.fps  -> max_frames_between_keyframes (ORB-SLAM2's mMaxFrames: a keyframe at least once a
//                  second), rounded, at least 1
//   ThDepth     -> close_depth_baselines (close / far split, in baselines; ORB-SLAM3: Stereo.ThDepth)
//   Tracker.stationaryTestChi2, .rotationOnlyTestChi2 -> the stationary test (0: off, as ORB-SLAM2)
//   Tracker.ransacSeed -> ransac_seed (repeatability experiments)
//   Tracker.revisitMinAgeS, .revisitMinOldInlierShare -> the revisit rule (0 s: off, as ORB-SLAM2)
// The other TrackerOptions fields are constants (tracker_options.hpp): a file giving one of their old
// Tracker.* keys is told it is not used.
// A missing key keeps the default; a wrong type or a value out of range is one error naming the
// source and the key (yaml_option).
#pragma once

#include <string>

#include <opencv2/core/persistence.hpp>

#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

void read_tracker_settings(const cv::FileNode& root, const std::string& source, TrackerOptions& options);

}  // namespace heslam
