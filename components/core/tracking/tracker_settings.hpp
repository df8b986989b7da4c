// The tracker's options from an ORB-SLAM2 settings file (config/camera/*.yaml), the file a user of
// ORB-SLAM edits: its standard keys with ORB-SLAM2's meaning, heslam's own under Tracker.*.
//   Camera.fps  -> max_frames_between_keyframes (ORB-SLAM2's mMaxFrames: a keyframe at least once a
//                  second), rounded, at least 1
//   ThDepth     -> close_depth_baselines (close / far split, in baselines)
//   Tracker.X   -> the TrackerOptions field X names (camelCase of the field; docs/configuration.md)
// A missing key keeps the default; a wrong type or a value out of range is one error naming the
// source and the key (yaml_option).
#pragma once

#include <string>

#include <opencv2/core/persistence.hpp>

#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

void read_tracker_settings(const cv::FileNode& root, const std::string& source, TrackerOptions& options);

}  // namespace heslam
