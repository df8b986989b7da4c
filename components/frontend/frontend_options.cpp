// Reading FrontendOptions from the component's YAML config; defaults are the core structs' own.
#include "components/frontend/frontend_options.hpp"

#include <climits>
#include <cmath>
#include <stdexcept>

#include "components/core/place/vocabulary_setting.hpp"
#include "components/core/tracking/settings_file.hpp"
#include "runtime/flags.hpp"

namespace heslam::frontend {
namespace {

constexpr double kMaxTimeoutS = 3600.0;

void read(const runtime::Config& c, const char* key, int& value, int min, int max) {
  value = c.get_int(key, value, min, max);
}
void read(const runtime::Config& c, const char* key, double& value, double min, double max) {
  value = c.get_double(key, value, min, max);
}
void read(const runtime::Config& c, const char* key, bool& value) { value = c.get_bool(key, value); }

// One name per tunable: the vision and tracking options are the settings file's, not the config's.
void refuse_moved_sections(const runtime::Config& c) {
  for (const char* section : {"he", "orb", "stereo", "pipeline", "tracker"}) {
    if (!c.has(section)) continue;
    throw std::runtime_error(c.source() + ": field '" + section +
                             "': vision and tracking options are read from the settings file (settings.file or "
                             "--settings FILE, an ORB-SLAM2 settings file such as config/camera/EuRoC.yaml: HE.*, "
                             "ORBextractor.*, Stereo.*, Pipeline.*, ThDepth, Camera.fps, Tracker.*; "
                             "docs/configuration.md)");
  }
}

// imu.*: off unless imu.enabled (docs/frontend.md, Inertial tracking).
InertialOptions read_inertial(const runtime::Config& c) {
  InertialOptions o;
  read(c, "imu.enabled", o.enabled);
  read(c, "imu.lockstep", o.lockstep);
  read(c, "imu.wait_s", o.wait_s, 0.01, kMaxTimeoutS);
  read(c, "imu.init_min_duration_s", o.init_min_duration_s, 0.1, 60.0);
  read(c, "imu.init_min_keyframes", o.init_min_keyframes, 3, 1000);
  read(c, "imu.init_max_keyframes", o.init_max_keyframes, 3, 1000);
  read(c, "imu.init_retry_s", o.init_retry_s, 0.0, 60.0);
  read(c, "imu.init_max_gravity_stddev_deg", o.init_max_gravity_stddev_deg, 0.01, 90.0);
  read(c, "imu.init_max_accel_bias_stddev_m_s2", o.init_max_accel_bias_stddev_m_s2, 0.001, 100.0);
  read(c, "imu.init_max_gravity_stddev_of_prior", o.init_max_gravity_stddev_of_prior, 0.01, 1000.0);
  read(c, "imu.refine_every_s", o.refine_every_s, 0.05, 60.0);
  read(c, "imu.refine_until_s", o.refine_until_s, 0.0, 3600.0);
  read(c, "imu.blackout_max_s", o.blackout_max_s, 0.0, 60.0);
  read(c, "imu.velocity_window_s", o.velocity_window_s, 0.05, 10.0);
  read(c, "imu.pose_optimization", o.pose_optimization);
  read(c, "imu.pose_prior_rotation_rad", o.pose_prior_rotation_rad, 1e-9, 1.0);
  read(c, "imu.pose_prior_position_m", o.pose_prior_position_m, 1e-9, 10.0);
  read(c, "imu.pose_prior_velocity_m_s", o.pose_prior_velocity_m_s, 1e-9, 10.0);
  read(c, "imu.pose_optimization_max_gravity_stddev_deg", o.pose_optimization_max_gravity_stddev_deg, 0.0, 90.0);
  if (o.init_max_keyframes < o.init_min_keyframes) {
    throw std::runtime_error(c.source() + ": field 'imu.init_max_keyframes': " + std::to_string(o.init_max_keyframes) +
                             " is below imu.init_min_keyframes (" + std::to_string(o.init_min_keyframes) + ")");
  }
  return o;
}

}  // namespace

FrontendOptions FrontendOptions::from_config(const runtime::Config& config, const std::vector<std::string>& rest) {
  FrontendOptions options;
  refuse_moved_sections(config);
  read(config, "lockstep.wait_for_mapper", options.wait_for_mapper);
  options.mapper_enabled = config.get_bool("mapper.enabled", options.wait_for_mapper);
  options.wait_for_mapper = options.wait_for_mapper && options.mapper_enabled;
  double timeout_s = std::chrono::duration<double>(options.mapper_timeout).count();
  read(config, "lockstep.mapper_timeout_s", timeout_s, 0.1, kMaxTimeoutS);
  options.mapper_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  read(config, "frames.max_pending", options.max_pending_frames, 1, 1000);
  options.shedding = LoadSheddingOptions::from_config(config, options.wait_for_mapper);
  options.vocabulary_file = config.get_string("vocabulary.file", "");
  options.vocabulary = load_vocabulary_setting(options.vocabulary_file);
  options.mapper_map_file = config.get_string("mapper.map_file", "");
  options.journal_file = config.get_string("journal.file", "");
  options.settings_file = config.get_path("settings.file", "");
  options.inertial = read_inertial(config);
  read(config, "atlas.new_map_after_s", options.new_map_after_s, 0.0, kMaxTimeoutS);
  read(config, "session.new_map_after_s", options.session_new_map_after_s, 0.0, kMaxTimeoutS);
  std::string imu = "auto";
  std::string loop_closer = config.get_string("lockstep.loop_closer", "none");
  const std::string loop_closer_name = config.get_string("lockstep.loop_closer_name", "loop_closer");
  runtime::Flags flags("heslam-frontend [options]");
  flags
      .custom("--settings", "FILE", "ORB-SLAM2 settings file (empty: the config's settings.file)",
              [&options](const std::string& value) {
                if (!value.empty()) options.settings_file = value;
              })
      .path("--mapper-map-file", "FILE", &options.mapper_map_file, "the local mapper's map file (mapper.map_file)")
      .path("--journal", "FILE", &options.journal_file, "the odometry journal (journal.file)")
      .text("--loop-closer", "EXECUTABLE|none", &loop_closer,
            "the loop closer of a lockstep run (lockstep.loop_closer)")
      .toggle("--localize", &options.localize, "track against the saved map of --mapper-map-file")
      .toggle("--session", &options.session,
              "map on in the saved map of --mapper-map-file (a new map, merged later, when not relocalized)")
      .custom("--mapping", "on|off", "off: localization only (with --localize): no keyframe or point is created",
              [&options](const std::string& value) {
                if (value != "on" && value != "off") runtime::throw_bad_flag_value("--mapping", "on or off", value);
                options.mapping = value == "on";
              })
      .path("--saved-map", "FILE", &options.saved_map, "the saved map the mapper loaded (named in messages)")
      .integer("--agent", "N", &options.agent, 0, kMaxAgentId,
               "agent id of this frontend (several agents, docs/agents.md): in its keyframe, point and map ids")
      .custom("--imu", "auto|none", "none: no inertial tracking whatever imu.enabled says (auto: imu.enabled)",
              [&imu](const std::string& value) {
                if (value != "auto" && value != "none") runtime::throw_bad_flag_value("--imu", "auto or none", value);
                imu = value;
              });
  flags.parse(rest);
  if (imu == "none") options.inertial.enabled = false;
  if (!options.mapping && !options.localize) {
    throw std::runtime_error("--mapping off: localization only needs a saved map to localize in (--localize)");
  }
  if (options.localize && (options.mapper_map_file.empty() || !options.mapper_enabled)) {
    throw std::runtime_error(
        "--localize: needs the local mapper (mapper.enabled) and its map file (--mapper-map-file FILE)");
  }
  if (options.session && options.localize) {
    throw std::runtime_error(
        "--session and --localize: a session maps on in the saved map, --localize only "
        "tracks in it; give one of them");
  }
  if (options.session && (options.mapper_map_file.empty() || !options.mapper_enabled)) {
    throw std::runtime_error(
        "--session: needs the local mapper (mapper.enabled) and its map file (--mapper-map-file FILE)");
  }
  if (!loop_closer.empty() && loop_closer != "none" && options.wait_for_mapper) {
    options.loop_closers.push_back(loop_closer_name);
  }

  // The settings file's options over the defaults; with a mapper, whose local BA refines the points a
  // near-clip match gave, the reference-ratio rule counts near-clip points fully (measured with the
  // cameras exposed apart, docs/benchmarks.md at 5c1f792, gain5) unless the file says otherwise.
  TrackerOptions tracker_defaults;
  if (options.mapper_enabled) tracker_defaults.reference_near_clip_weight = 0.0;
  options.tracker = tracker_defaults;
  if (!options.settings_file.empty()) {
    SettingsFile settings = load_settings_file(options.settings_file, tracker_defaults);
    options.features = settings.pipeline;
    options.tracker = settings.tracker;
    options.settings_unused_keys = std::move(settings.unused_keys);
    options.settings_camera_fx = settings.camera_fx;
    options.settings_camera_bf = settings.camera_bf;
  }

  // With a mapper the frontend mirrors the map instead of maintaining it; its ids stay the frontend's.
  options.tracker.maintain_map = !options.mapper_enabled;
  options.tracker.id_tag = frontend_tag(options.agent);
  options.tracker.first_map_id = first_map_id(options.agent);
  options.tracker.create_keyframes = options.mapping;
  // A localization run's poses are worth something only in the saved map: a new map there would end the
  // run with a trajectory in another frame (and hide "never relocalized in the saved map"), so it waits.
  options.tracker.new_map_after_ns = options.localize  ? 0
                                     : options.session ? std::llround(options.session_new_map_after_s * 1e9)
                                                       : std::llround(options.new_map_after_s * 1e9);
  return options;
}

std::string never_relocalized_message(const FrontendOptions& options, std::uint64_t frames) {
  std::string map = options.saved_map.empty() ? options.mapper_map_file.string() : options.saved_map.string();
  if (!options.saved_map.empty() && options.saved_map != options.mapper_map_file) {
    map += ", loaded into " + options.mapper_map_file.string();
  }
  return "never relocalized in the saved map (" + map + "): " + std::to_string(frames) + " frames, none tracked";
}

}  // namespace heslam::frontend
