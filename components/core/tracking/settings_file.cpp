// An ORB-SLAM2 settings file -> the vision pipeline's and the tracker's options (settings_file.hpp).
#include "components/core/tracking/settings_file.hpp"

#include <algorithm>
#include <array>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/image/yaml_option.hpp"
#include "components/core/tracking/tracker_settings.hpp"

namespace heslam {
namespace {

// The calibration's keys (ORB-SLAM2's stereo settings; stereo_calibration.hpp reads them).
constexpr std::array<std::string_view, 13> kCameraKeys{
    "Camera.fx", "Camera.fy", "Camera.cx",    "Camera.cy",     "Camera.k1", "Camera.k2", "Camera.p1",
    "Camera.p2", "Camera.k3", "Camera.width", "Camera.height", "Camera.bf", "Camera.fps"};
constexpr std::array<std::string_view, 6> kRectificationKeys{"height", "width", "D", "K", "R", "P"};

// ORB-SLAM3's (File.version "1.0"): the format and rig keys; Camera1.* / Camera2.* hold the intrinsics.
constexpr std::array<std::string_view, 6> kOrbSlam3RigKeys{"File.version", "Camera.type", "Stereo.T_c1_c2",
                                                           "Stereo.b",     "IMU.T_b_c1",  "Camera.RGB"};

bool calibration_key(const std::string& key) {
  if (std::find(kCameraKeys.begin(), kCameraKeys.end(), key) != kCameraKeys.end()) return true;
  if (std::find(kOrbSlam3RigKeys.begin(), kOrbSlam3RigKeys.end(), key) != kOrbSlam3RigKeys.end()) return true;
  for (const std::string_view camera : {"Camera1.", "Camera2."}) {
    if (key.rfind(camera, 0) != 0) continue;
    const std::string_view field = std::string_view(key).substr(camera.size());
    // k4: KannalaBrandt8; overlapping*: ORB-SLAM3's fisheye overlap, read and ignored by the loader.
    for (const std::string_view known :
         {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "overlappingBegin", "overlappingEnd"}) {
      if (field == known) return true;
    }
  }
  for (const std::string_view side : {"LEFT.", "RIGHT."}) {
    if (key.rfind(side, 0) != 0) continue;
    const std::string_view field = std::string_view(key).substr(side.size());
    if (std::find(kRectificationKeys.begin(), kRectificationKeys.end(), field) != kRectificationKeys.end()) return true;
  }
  return false;
}

double number_or_zero(const cv::FileNode& root, const char* key) {
  const cv::FileNode node = root[key];
  return node.isReal() || node.isInt() ? static_cast<double>(node) : 0.0;
}

}  // namespace

SettingsFile load_settings_file(const std::filesystem::path& path, const TrackerOptions& tracker_defaults) {
  cv::FileStorage fs;
  try {
    fs.open(path.string(), cv::FileStorage::READ);
  } catch (const cv::Exception& error) {
    throw std::runtime_error(path.string() + ": not a valid settings file (" + error.msg + ")");
  }
  if (!fs.isOpened()) throw std::runtime_error(path.string() + ": cannot open the settings file");
  const cv::FileNode root = fs.root();
  const std::string source = path.string();
  SettingsFile settings;
  settings.path = path;
  settings.tracker = tracker_defaults;
  {
    const yaml_option::KeyLog read;
    settings.pipeline = StereoFeaturePipelineOptions::from_yaml(root, source);
    read_tracker_settings(root, source, settings.tracker);
    for (const std::string& key : root.keys()) {
      if (read.keys().count(key) == 0 && !calibration_key(key)) settings.unused_keys.push_back(key);
    }
  }
  if (!root["File.version"].empty()) {
    // ORB-SLAM3's format: its calibration loader refuses what heslam cannot honour (a fisheye model, a
    // resize), in one line naming the key; the fx and bf to compare with the data come from its keys.
    // Compared as the rectified model, as the data's is (Camera1.fx of a raw pair is not).
    const PinholeStereo rectified = StereoRectifier(load_orbslam_settings(path)).camera();
    settings.camera_fx = rectified.fx_px;
    settings.camera_bf = rectified.bf();
    return settings;
  }
  settings.camera_fx = number_or_zero(root, "Camera.fx");
  settings.camera_bf = number_or_zero(root, "Camera.bf");
  return settings;
}

std::string describe_settings(const StereoFeaturePipelineOptions& p, const TrackerOptions& t) {
  // Every settings key's value (docs/frontend.md), so that a user's edit shows in the start-up line.
  std::ostringstream line;
  line << "HE " << to_string(p.he.mode) << " (stereo " << to_string(p.he.stereo) << ", clip " << p.he.global_clip_limit
       << ", CLAHE " << p.he.clahe_clip_limit << " on " << p.he.clahe_tiles_x << "x" << p.he.clahe_tiles_y
       << ", adaptive on below " << p.he.adaptive_on_below << " off above " << p.he.adaptive_off_above << ")"
       << "; ORB " << p.orb.features << " features, scale " << p.orb.scale_factor << " x " << p.orb.levels
       << " levels, FAST " << p.orb.fast_threshold_initial << "/" << p.orb.fast_threshold_min << "; stereo row band "
       << p.stereo.row_band_px << "; pipeline "
       << (p.parallel ? (p.pin_threads ? "parallel (pinned)" : "parallel (unpinned)") : "serial")
       << ", left-only features " << p.left_only_features << "; tracker ThDepth " << t.close_depth_baselines
       << " baselines, keyframe at least every " << t.max_frames_between_keyframes << " frames, stationary test "
       << t.stationary_test_chi2 << "/" << t.rotation_only_test_chi2 << ", RANSAC seed " << t.ransac_seed
       << ", revisits after " << t.revisit_min_age_s << " s (old inliers " << t.revisit_min_old_inlier_share << ")";
  return line.str();
}

}  // namespace heslam
