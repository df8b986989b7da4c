// The one file a user edits for vision and tracking: an ORB-SLAM2 stereo settings file
// (config/camera/*.yaml). The frontend, the offline harness and the benchmarks read it here, so a
// key means the same everywhere (docs/configuration.md, Settings file):
//   HE.*, ORBextractor.*, Stereo.*, Pipeline.*  -> StereoFeaturePipelineOptions::from_yaml
//   Camera.fps, ThDepth, Tracker.*               -> read_tracker_settings
//   Camera.fx ... Camera.bf, LEFT.*, RIGHT.*    -> the calibration's keys: the calibration itself
//                                                  comes with the data (the replay's camera/calibration);
//                                                  the frontend compares Camera.fx and Camera.bf with it
// Any other key is named in `unused_keys` (a typo, or a key of ORB-SLAM2's viewer): the caller warns.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct SettingsFile {
  std::filesystem::path path;
  StereoFeaturePipelineOptions pipeline;
  TrackerOptions tracker;                // the defaults given, with the file's keys applied
  std::vector<std::string> unused_keys;  // in the file, read by nothing in heslam
  // The calibration keys as written (0 when absent), for the comparison with the data's calibration.
  double camera_fx = 0.0;
  double camera_bf = 0.0;
};

// Throws std::runtime_error naming the file and the key on a file that cannot be read or a value of
// the wrong type or out of range.
SettingsFile load_settings_file(const std::filesystem::path& path, const TrackerOptions& tracker_defaults = {});

// One line of the effective options, "HE clipped (clip 2, ...), ORB 1200 features x 8 levels ...",
// for start-up logs: a test and a user can see what a run uses.
std::string describe_settings(const StereoFeaturePipelineOptions& pipeline, const TrackerOptions& tracker);

}  // namespace heslam
