// Preset files: YAML read with cv::FileStorage, with one-line errors naming file and field.
#include "tools/synth/preset.hpp"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include <opencv2/core.hpp>

#ifndef HESLAM_SYNTH_PRESET_DIR
#define HESLAM_SYNTH_PRESET_DIR ""
#endif

namespace heslam::synth {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const fs::path& file, const std::string& field, const std::string& what) {
  throw std::runtime_error(file.string() + ": field '" + field + "' " + what);
}

void read_number(const cv::FileNode& parent, const char* key, const std::string& prefix, const fs::path& file,
                 double& value) {
  const cv::FileNode n = parent[key];
  if (n.empty() || n.isNone()) return;
  if (!n.isReal() && !n.isInt()) fail(file, prefix + key, "expected a number");
  value = static_cast<double>(n);
}

void read_int(const cv::FileNode& parent, const char* key, const std::string& prefix, const fs::path& file,
              int& value) {
  const cv::FileNode n = parent[key];
  if (n.empty() || n.isNone()) return;
  if (!n.isInt()) fail(file, prefix + key, "expected an integer");
  value = static_cast<int>(n);
}

void require_positive(double value, const std::string& field, const fs::path& file) {
  if (!(value > 0.0)) fail(file, field, "must be positive");
}

SceneKind parse_scene(const std::string& s, const fs::path& file) {
  if (s == "room") return SceneKind::kRoom;
  if (s == "corridor_loop") return SceneKind::kCorridorLoop;
  if (s == "street") return SceneKind::kStreet;
  if (s == "town") return SceneKind::kTown;
  if (s == "marker_wall") return SceneKind::kMarkerWall;
  fail(file, "scene", "is '" + s + "', expected room, corridor_loop, street, town or marker_wall");
}

EventKind parse_event(const std::string& s, const std::string& field, const fs::path& file) {
  if (s == "overexposure") return EventKind::kOverexposure;
  if (s == "darkness") return EventKind::kDarkness;
  if (s == "haze") return EventKind::kHaze;
  if (s == "drift") return EventKind::kDrift;
  if (s == "stereo_gain") return EventKind::kStereoGain;
  fail(file, field, "is '" + s + "', expected overexposure, darkness, haze, drift or stereo_gain");
}

// The camera: map of a preset or a camera file over `camera` (the fields given), then checked.
void read_camera(const cv::FileNode& cam, const fs::path& f, CameraSpec& camera) {
  if (!cam.empty()) {
    if (!cam.isMap()) fail(f, "camera", "expected a map");
    read_int(cam, "width", "camera.", f, camera.width_px);
    read_int(cam, "height", "camera.", f, camera.height_px);
    read_number(cam, "fx", "camera.", f, camera.fx_px);
    read_number(cam, "fy", "camera.", f, camera.fy_px);
    read_number(cam, "cx", "camera.", f, camera.cx_px);
    read_number(cam, "cy", "camera.", f, camera.cy_px);
    read_number(cam, "baseline_m", "camera.", f, camera.baseline_m);
    read_number(cam, "rate_hz", "camera.", f, camera.rate_hz);
    const cv::FileNode model = cam["distortion_model"];
    if (!model.empty() && !model.isNone()) {
      const std::string name = model.isString() ? static_cast<std::string>(model) : "";
      if (name == "equidistant") {
        camera.lens = LensModel::kEquidistant;
      } else if (name == "radial-tangential" || name == "radtan") {
        camera.lens = LensModel::kRadialTangential;
      } else {
        fail(f, "camera.distortion_model",
             "is '" + name.substr(0, 40) + "', expected radial-tangential or equidistant");
      }
    }
    const bool fisheye = camera.lens == LensModel::kEquidistant;
    const char* expected_coefficients = fisheye ? "expected [k1, k2, k3, k4]" : "expected [k1, k2, p1, p2]";
    const cv::FileNode d = cam["distortion"];
    if (fisheye && (d.empty() || d.isNone() || !d.isSeq() || d.size() != 4)) {
      fail(f, "camera.distortion", std::string(expected_coefficients) + " (an equidistant lens has 4 coefficients)");
    }
    if (!d.empty() && !d.isNone()) {
      if (!d.isSeq() || (d.size() != 4 && d.size() != 0)) fail(f, "camera.distortion", expected_coefficients);
      camera.distortion.clear();
      for (const auto& v : d) {
        if (!v.isReal() && !v.isInt()) fail(f, "camera.distortion", "expected numbers");
        camera.distortion.push_back(static_cast<double>(v));
      }
    }
  }
  if (camera.width_px < 32 || camera.height_px < 32) fail(f, "camera.width/height", "must be >= 32");
  require_positive(camera.fx_px, "camera.fx", f);
  require_positive(camera.fy_px, "camera.fy", f);
  require_positive(camera.baseline_m, "camera.baseline_m", f);
  require_positive(camera.rate_hz, "camera.rate_hz", f);
}

}  // namespace

std::string to_string(SceneKind kind) {
  switch (kind) {
    case SceneKind::kRoom: return "room";
    case SceneKind::kCorridorLoop: return "corridor_loop";
    case SceneKind::kStreet: return "street";
    case SceneKind::kTown: return "town";
    case SceneKind::kMarkerWall: return "marker_wall";
  }
  return "?";
}

std::string to_string(EventKind kind) {
  switch (kind) {
    case EventKind::kOverexposure: return "overexposure";
    case EventKind::kDarkness: return "darkness";
    case EventKind::kHaze: return "haze";
    case EventKind::kDrift: return "drift";
    case EventKind::kStereoGain: return "stereo_gain";
  }
  return "?";
}

namespace {

// A preset or camera file opened for reading; `what` names it in the error ("preset file").
cv::FileStorage open_yaml(const fs::path& yaml_path, const std::string& what) {
  if (!fs::exists(yaml_path)) throw std::runtime_error(yaml_path.string() + ": " + what + " does not exist");
  cv::FileStorage fs_in;
  try {
    fs_in.open(yaml_path.string(), cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(yaml_path.string() + ": not readable as YAML (" + e.err + ")");
  }
  if (!fs_in.isOpened()) throw std::runtime_error(yaml_path.string() + ": cannot be opened as YAML");
  return fs_in;
}

}  // namespace

Preset load_preset(const fs::path& yaml_path) {
  const cv::FileStorage fs_in = open_yaml(yaml_path, "preset file");
  const cv::FileNode root = fs_in.root();
  const fs::path& f = yaml_path;

  Preset p;
  p.source = yaml_path;
  p.name = yaml_path.stem().string();
  if (!root["name"].empty()) p.name = static_cast<std::string>(root["name"]);
  if (!root["purpose"].empty()) {
    if (!root["purpose"].isString()) fail(f, "purpose", "expected a string");
    p.purpose = static_cast<std::string>(root["purpose"]);
  }
  if (root["scene"].empty()) fail(f, "scene", "is missing (room, corridor_loop, street, town or marker_wall)");
  if (!root["scene"].isString()) fail(f, "scene", "expected a string");
  p.scene = parse_scene(static_cast<std::string>(root["scene"]), f);
  read_int(root, "frames", "", f, p.frames);
  if (p.frames <= 0) fail(f, "frames", "must be positive");
  read_int(root, "texture_size_px", "", f, p.texture_size_px);
  if (p.texture_size_px < 16 || (p.texture_size_px & (p.texture_size_px - 1)) != 0)
    fail(f, "texture_size_px", "must be a power of two >= 16");
  if (!root["photo_dir"].empty()) p.photo_dir = static_cast<std::string>(root["photo_dir"]);

  read_camera(root["camera"], f, p.camera);

  const cv::FileNode tr = root["trajectory"];
  if (!tr.empty()) {
    const std::string pre = "trajectory.";
    read_number(tr, "speed_mps", pre, f, p.trajectory.speed_mps);
    read_number(tr, "accel_time_s", pre, f, p.trajectory.accel_time_s);
    read_number(tr, "lateral_jitter_m", pre, f, p.trajectory.lateral_jitter_m);
    read_number(tr, "height_jitter_m", pre, f, p.trajectory.height_jitter_m);
    read_number(tr, "yaw_offset_deg", pre, f, p.trajectory.yaw_offset_deg);
    read_number(tr, "pitch_offset_deg", pre, f, p.trajectory.pitch_offset_deg);
    read_number(tr, "yaw_wiggle_deg", pre, f, p.trajectory.yaw_wiggle_deg);
    read_number(tr, "pitch_wiggle_deg", pre, f, p.trajectory.pitch_wiggle_deg);
    read_number(tr, "roll_wiggle_deg", pre, f, p.trajectory.roll_wiggle_deg);
    read_number(tr, "wiggle_hz", pre, f, p.trajectory.wiggle_hz);
    int stop_at_end = p.trajectory.stop_at_end ? 1 : 0;
    read_int(tr, "stop_at_end", pre, f, stop_at_end);
    p.trajectory.stop_at_end = stop_at_end != 0;
    read_number(tr, "teleport_at_s", pre, f, p.trajectory.teleport_at_s);
    read_number(tr, "teleport_m", pre, f, p.trajectory.teleport_m);
    if (p.trajectory.teleport_m < 0) fail(f, pre + "teleport_m", "must be >= 0 (metres further along the path)");
    if (p.trajectory.teleport_m > 0 && !(p.trajectory.teleport_at_s > 0)) {
      fail(f, pre + "teleport_at_s", "must be > 0 with a teleport (the time of the jump, seconds)");
    }
    const cv::FileNode stops = tr["stops"];
    if (!stops.empty() && !stops.isNone()) {
      if (!stops.isSeq()) fail(f, pre + "stops", "expected a list of {at_m, wait_s}");
      int i = 0;
      for (const auto& node : stops) {
        const std::string stop_pre = pre + "stops[" + std::to_string(i++) + "].";
        if (!node.isMap()) fail(f, stop_pre.substr(0, stop_pre.size() - 1), "expected a map");
        StopSpec stop;
        read_number(node, "at_m", stop_pre, f, stop.at_m);
        read_number(node, "wait_s", stop_pre, f, stop.wait_s);
        const double previous = p.trajectory.stops.empty() ? 0.0 : p.trajectory.stops.back().at_m;
        if (!(stop.at_m > previous)) fail(f, stop_pre + "at_m", "must be positive and increase from stop to stop");
        if (stop.wait_s < 0) fail(f, stop_pre + "wait_s", "must be >= 0");
        p.trajectory.stops.push_back(stop);
      }
    }
  }
  require_positive(p.trajectory.speed_mps, "trajectory.speed_mps", f);

  const cv::FileNode ph = root["photometry"];
  if (!ph.empty()) {
    const std::string pre = "photometry.";
    read_number(ph, "exposure", pre, f, p.photometry.exposure);
    read_number(ph, "full_well_e", pre, f, p.photometry.full_well_e);
    read_number(ph, "read_noise_dn", pre, f, p.photometry.read_noise_dn);
    read_number(ph, "vignetting", pre, f, p.photometry.vignetting);
    read_number(ph, "lens_blur_px", pre, f, p.photometry.lens_blur_px);
    read_number(ph, "haze_airlight", pre, f, p.photometry.haze_airlight);
    read_int(ph, "motion_blur_samples", pre, f, p.photometry.motion_blur_samples);
    read_number(ph, "exposure_time_s", pre, f, p.photometry.exposure_time_s);
    int noise = p.photometry.noise ? 1 : 0;
    read_int(ph, "noise", pre, f, noise);
    p.photometry.noise = noise != 0;
  }
  require_positive(p.photometry.exposure, "photometry.exposure", f);
  require_positive(p.photometry.full_well_e, "photometry.full_well_e", f);
  if (p.photometry.lens_blur_px < 0) fail(f, "photometry.lens_blur_px", "must be >= 0");
  if (p.photometry.motion_blur_samples < 1) fail(f, "photometry.motion_blur_samples", "must be >= 1");

  const cv::FileNode ev = root["events"];
  if (!ev.empty() && !ev.isNone()) {
    if (!ev.isSeq()) fail(f, "events", "expected a list of events");
    int i = 0;
    for (const auto& e : ev) {
      const std::string pre = "events[" + std::to_string(i++) + "].";
      if (!e.isMap()) fail(f, pre.substr(0, pre.size() - 1), "expected a map");
      if (e["type"].empty() || !e["type"].isString())
        fail(f, pre + "type", "expected overexposure, darkness, haze, drift or stereo_gain");
      ExposureEvent event;
      event.kind = parse_event(static_cast<std::string>(e["type"]), pre + "type", f);
      read_number(e, "start_s", pre, f, event.start_s);
      read_number(e, "end_s", pre, f, event.end_s);
      read_number(e, "strength", pre, f, event.strength);
      read_number(e, "ramp_s", pre, f, event.ramp_s);
      read_number(e, "left", pre, f, event.left);
      read_number(e, "right", pre, f, event.right);
      if (event.kind == EventKind::kStereoGain) {
        if (e["left"].empty() && e["right"].empty()) fail(f, pre + "left", "stereo_gain needs left and/or right");
        if (!(event.left > 0)) fail(f, pre + "left", "must be positive");
        if (!(event.right > 0)) fail(f, pre + "right", "must be positive");
      } else if (!e["left"].empty() || !e["right"].empty()) {
        fail(f, pre + "left", "only stereo_gain events have left / right gains");
      }
      if (!(event.end_s > event.start_s)) fail(f, pre + "end_s", "must be after start_s");
      if (event.ramp_s < 0 || 2 * event.ramp_s > event.end_s - event.start_s)
        fail(f, pre + "ramp_s", "must be >= 0 and at most half the event");
      if (!(event.strength > 0)) fail(f, pre + "strength", "must be positive");
      if (event.kind == EventKind::kHaze && event.strength > 1.0)
        fail(f, pre + "strength", "haze fraction must be <= 1");
      p.events.push_back(event);
    }
  }
  return p;
}

std::vector<std::string> known_presets() {
  std::vector<std::string> names;
  const fs::path dir = HESLAM_SYNTH_PRESET_DIR;
  if (!dir.empty() && fs::is_directory(dir)) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

void apply_camera_file(const fs::path& yaml_path, Preset& preset) {
  const cv::FileStorage fs_in = open_yaml(yaml_path, "camera file");
  const cv::FileNode camera = fs_in.root()["camera"];
  if (camera.empty() || !camera.isMap()) fail(yaml_path, "camera", "is missing (a map of a preset's camera fields)");
  read_camera(camera, yaml_path, preset.camera);
}

fs::path find_camera(const std::string& name_or_path) {
  const fs::path as_path = name_or_path;
  if (as_path.extension() == ".yaml" || as_path.extension() == ".yml") {
    if (!fs::exists(as_path)) throw std::runtime_error(as_path.string() + ": camera file does not exist");
    return as_path;
  }
  const fs::path dir = fs::path(HESLAM_SYNTH_PRESET_DIR) / "cameras";
  if (fs::exists(dir / (name_or_path + ".yaml"))) return dir / (name_or_path + ".yaml");
  std::vector<std::string> names;
  if (fs::is_directory(dir)) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
    }
  }
  std::sort(names.begin(), names.end());
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  throw std::runtime_error("unknown camera '" + name_or_path + "' (known: " + (list.empty() ? "none found" : list) +
                           "; or pass a path to a .yaml file)");
}

fs::path find_preset(const std::string& name_or_path) {
  const fs::path as_path = name_or_path;
  if (as_path.extension() == ".yaml" || as_path.extension() == ".yml") {
    if (!fs::exists(as_path)) throw std::runtime_error(as_path.string() + ": preset file does not exist");
    return as_path;
  }
  const fs::path in_tree = fs::path(HESLAM_SYNTH_PRESET_DIR) / (name_or_path + ".yaml");
  if (fs::exists(in_tree)) return in_tree;
  std::string list;
  for (const auto& n : known_presets()) list += (list.empty() ? "" : ", ") + n;
  throw std::runtime_error("unknown preset '" + name_or_path + "' (known: " + (list.empty() ? "none found" : list) +
                           "; or pass a path to a .yaml file)");
}

}  // namespace heslam::synth
