// A synthetic sequence preset (config/synth/<name>.yaml): scene kind, camera, trajectory, photometry
// and exposure events. Read with cv::FileStorage; every field has the default documented below.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace heslam::synth {

enum class SceneKind { kRoom, kCorridorLoop, kStreet, kTown, kMarkerWall };

// The raw camera's lens: pinhole with radial-tangential distortion (k1 k2 p1 p2), or equidistant
// (Kannala-Brandt) fisheye (k1 k2 k3 k4, components/core/camera/equidistant.hpp).
enum class LensModel { kRadialTangential, kEquidistant };

struct CameraSpec {
  int width_px = 752;
  int height_px = 480;
  double fx_px = 458.654;
  double fy_px = 457.296;
  double cx_px = 367.215;
  double cy_px = 248.375;
  LensModel lens = LensModel::kRadialTangential;
  // radial-tangential k1 k2 p1 p2, or equidistant k1 k2 k3 k4; empty = ideal pinhole (radtan only)
  std::vector<double> distortion;
  double baseline_m = 0.11;  // right camera sits baseline_m along +x of the left camera
  double rate_hz = 20.0;
};

// A stop along the path: brake to rest at `at_m` (arc length along the trajectory), wait, drive on.
struct StopSpec {
  double at_m = 0.0;
  double wait_s = 0.0;
};

struct TrajectorySpec {
  double speed_mps = 0.8;         // cruising speed along the path
  double accel_time_s = 1.5;      // time to reach cruising speed from rest at the start
  double lateral_jitter_m = 0.3;  // seeded sideways displacement of the path's control points
  double height_jitter_m = 0.1;   // seeded vertical displacement of the path's control points
  double yaw_offset_deg = 0.0;    // constant heading offset from the direction of travel
  double pitch_offset_deg = 5.0;  // constant downward look (positive = nose down)
  double yaw_wiggle_deg = 15.0;   // amplitude of the seeded smooth heading oscillation
  double pitch_wiggle_deg = 4.0;
  double roll_wiggle_deg = 2.0;
  double wiggle_hz = 0.2;  // base frequency of the oscillations (two harmonics are added)
  // Stops, braking and starting again at the accel_time_s rate (a constant speed profile without).
  // With stops or stop_at_end the oscillations follow the distance travelled (wiggle_hz at cruising
  // speed), so a vehicle at rest does not sway.
  std::vector<StopSpec> stops;
  bool stop_at_end = false;  // open paths: brake to rest at the end (without: stop dead there)
  // A teleport (the atlas's proof, docs/tools/synth.md): from teleport_at_s on the camera is
  // teleport_m further along the path, between two frames, with nothing in between (carried
  // somewhere the camera has not seen). 0 m: none. Not with --imu (no IMU can measure a jump).
  double teleport_at_s = 0.0;
  double teleport_m = 0.0;
};

struct PhotometrySpec {
  double exposure = 1.0;          // scene radiance 1.0 maps to this fraction of 255 DN
  double full_well_e = 6000.0;    // electrons at 255 DN: sets the shot noise
  double read_noise_dn = 1.2;     // Gaussian read noise, DN
  double vignetting = 0.3;        // relative brightness loss in the image corners (cos^4-like)
  double lens_blur_px = 0.6;      // Gaussian point-spread sigma of the lens + pixel area, pixels
  double haze_airlight = 0.85;    // radiance the haze converges to
  int motion_blur_samples = 1;    // 1 = off; N sub-renders averaged over the exposure time
  double exposure_time_s = 0.01;  // shutter time for motion blur
  bool noise = true;
};

enum class EventKind { kOverexposure, kDarkness, kHaze, kDrift, kStereoGain };

// One photometric event, active over [start_s, end_s] (seconds from the first frame).
//   overexposure / darkness: exposure gain multiplied by `strength` (e.g. 4.0 / 0.12), ramped over ramp_s
//   haze: radiance blended towards the airlight by fraction `strength` (0..1), ramped over ramp_s
//   drift: exposure gain follows strength^sin(pi * phase) — a slow swell that is back to 1 at end_s
//   stereo_gain: the left camera's exposure x `left`, the right camera's x `right` (cameras with their
//     own auto-exposure, a flared or shaded lens), ramped over ramp_s; `strength` is not used
struct ExposureEvent {
  EventKind kind = EventKind::kOverexposure;
  double start_s = 0.0;
  double end_s = 0.0;
  double strength = 1.0;
  double ramp_s = 0.1;
  double left = 1.0;   // stereo_gain only
  double right = 1.0;  // stereo_gain only
};

struct Preset {
  std::string name;
  std::string purpose;  // what the sequence tests, one line (heslam-synth --list)
  SceneKind scene = SceneKind::kRoom;
  int frames = 600;           // default sequence length (--frames overrides)
  int texture_size_px = 512;  // level-0 size of every texture (power of two)
  std::filesystem::path photo_dir = "/usr/share/doc/opencv-doc/examples/data";
  CameraSpec camera;
  TrajectorySpec trajectory;
  PhotometrySpec photometry;
  std::vector<ExposureEvent> events;
  std::filesystem::path source;  // file it was read from
};

std::string to_string(SceneKind kind);
std::string to_string(EventKind kind);

// Reads a preset file; throws std::runtime_error naming the file and field on bad content.
Preset load_preset(const std::filesystem::path& yaml_path);

// Finds a preset by name (config/synth/<name>.yaml in the source tree or next to the executable's
// share folder) or by path; throws listing the known presets when it does not exist.
std::filesystem::path find_preset(const std::string& name_or_path);

// A camera file (config/synth/cameras/NAME.yaml, e.g. fisheye): its camera: map, a preset's camera
// fields, laid over `preset`'s camera (heslam-synth --camera). Throws one line naming file and field.
void apply_camera_file(const std::filesystem::path& yaml_path, Preset& preset);
// NAME (config/synth/cameras/NAME.yaml) or a path to a .yaml file.
std::filesystem::path find_camera(const std::string& name_or_path);
std::vector<std::string> known_presets();

}  // namespace heslam::synth
