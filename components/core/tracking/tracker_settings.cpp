// ORB-SLAM2 settings keys -> TrackerOptions (see tracker_settings.hpp).
#include "components/core/tracking/tracker_settings.hpp"

#include <climits>
#include <cmath>

#include "components/core/image/yaml_option.hpp"

namespace heslam {
namespace {

void read_int(const cv::FileNode& root, const std::string& source, const char* key, int& value, int min, int max) {
  yaml_option::read(root, key, source, value);
  if (value < min || value > max) {
    yaml_option::fail(source, key, "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
}

template <typename Number>
void read_number(const cv::FileNode& root, const std::string& source, const char* key, Number& value, double min,
                 double max) {
  double read = value;
  yaml_option::read(root, key, source, read);
  if (!(read >= min && read <= max)) {
    yaml_option::fail(source, key, "a number in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  value = static_cast<Number>(read);
}

}  // namespace

void read_tracker_settings(const cv::FileNode& root, const std::string& source, TrackerOptions& t) {
  double fps = 0.0;
  yaml_option::read(root, "Camera.fps", source, fps);
  if (yaml_option::present(root, "Camera.fps")) {
    if (!(fps > 0.0) || fps > 10000.0) yaml_option::fail(source, "Camera.fps", "a frame rate in (0, 10000]");
    t.max_frames_between_keyframes = std::max(1, static_cast<int>(std::lround(fps)));
  }
  read_number(root, source, "ThDepth", t.close_depth_baselines, 1.0, 1000.0);
  // ORB-SLAM3 names the same threshold Stereo.ThDepth.
  if (yaml_option::present(root, "Stereo.ThDepth") && yaml_option::present(root, "ThDepth")) {
    yaml_option::fail(source, "Stereo.ThDepth", "one of ThDepth (ORB-SLAM2) and Stereo.ThDepth (ORB-SLAM3), not both");
  }
  read_number(root, source, "Stereo.ThDepth", t.close_depth_baselines, 1.0, 1000.0);

  // The stationary test is heslam's (not ORB-SLAM2's): 0 turns it off, ORB-SLAM2's behaviour.
  read_number(root, source, "Tracker.stationaryTestChi2", t.stationary_test_chi2, 0.0, 1e6);
  read_number(root, source, "Tracker.rotationOnlyTestChi2", t.rotation_only_test_chi2, 0.0, 1e6);
  int seed = static_cast<int>(t.ransac_seed);
  read_int(root, source, "Tracker.ransacSeed", seed, 0, INT_MAX);
  t.ransac_seed = static_cast<std::uint64_t>(seed);
  // The revisit rule (issue 41, not ORB-SLAM2's): 0 s turns it off, ORB-SLAM2's keyframe decision.
  read_number(root, source, "Tracker.revisitMinAgeS", t.revisit_min_age_s, 0.0, 1e6);
  read_number(root, source, "Tracker.revisitMinOldInlierShare", t.revisit_min_old_inlier_share, 0.0, 1.0);
}

}  // namespace heslam
