// Config and command-line reading of heslam-local-mapper's options.
#include "components/local_mapper/mapper_process_options.hpp"

#include <filesystem>

#include <stdexcept>

#include "components/core/map/ids.hpp"
#include "runtime/flags.hpp"

namespace heslam::local_mapper {
namespace {

// Bounds of the numeric options: wide enough for any sensible tuning, tight enough to reject typos.
constexpr int kMaxIterations = 1000;
constexpr int kMaxNeighbours = 100;
constexpr int kMaxThreads = 64;
constexpr int kMaxSharedPoints = 1000;
constexpr int kMaxSaveEvery = 1000000;
constexpr double kMaxReaderWaitS = 60.0;
constexpr double kMinCompactRatio = 0.01;  // below: a snapshot nearly every save, the journal pointless
constexpr double kMaxCompactRatio = 100.0;

}  // namespace

MapperProcessOptions MapperProcessOptions::from_config(const runtime::Config& config,
                                                       const std::vector<std::string>& rest) {
  MapperProcessOptions o;
  LocalMapperOptions& m = o.mapper;
  // An empty string means "none" (get_path would resolve it to the config folder).
  if (!config.get_string("map_file", "").empty()) o.map_file = config.get_path("map_file", {});
  if (!config.get_string("load_map", "").empty()) o.load_map = config.get_path("load_map", {});
  if (!config.get_string("save_map", "").empty()) o.save_map = config.get_path("save_map", {});
  o.real_time = config.get_bool("real_time", o.real_time);
  o.save_every_keyframes = config.get_int("save_every_keyframes", o.save_every_keyframes, 1, kMaxSaveEvery);
  o.sync_writes = config.get_bool("sync_writes", o.sync_writes);
  o.map_journal = config.get_bool("map_journal.enabled", o.map_journal);
  o.map_journal_compact_ratio =
      config.get_double("map_journal.compact_ratio", o.map_journal_compact_ratio, kMinCompactRatio, kMaxCompactRatio);
  o.map_journal_verify = config.get_bool("map_journal.verify", o.map_journal_verify);
  o.test_kill_after_saved_keyframes =
      config.get_int("test.kill_after_saved_keyframes", o.test_kill_after_saved_keyframes, 0, 1 << 30);
  o.batch_map_writes = config.get_bool("batch_map_writes", o.batch_map_writes);
  const double reader_wait_s = config.get_double("lockstep.reader_wait_s", 2.0, 0.0, kMaxReaderWaitS);
  o.reader_wait = std::chrono::milliseconds(static_cast<long long>(reader_wait_s * 1000.0));

  m.covisibility.min_shared_points =
      config.get_int("covisibility.min_shared_points", m.covisibility.min_shared_points, 1, kMaxSharedPoints);
  m.enable_triangulation = config.get_bool("triangulation.enabled", m.enable_triangulation);
  m.triangulation.neighbours =
      config.get_int("triangulation.neighbours", m.triangulation.neighbours, 1, kMaxNeighbours);
  m.enable_fusion = config.get_bool("fusion.enabled", m.enable_fusion);
  m.fusion.neighbours = config.get_int("fusion.neighbours", m.fusion.neighbours, 1, kMaxNeighbours);
  m.enable_bundle_adjustment = config.get_bool("bundle_adjustment.enabled", m.enable_bundle_adjustment);
  m.bundle_adjustment.first_pass_iterations = config.get_int(
      "bundle_adjustment.first_pass_iterations", m.bundle_adjustment.first_pass_iterations, 1, kMaxIterations);
  m.bundle_adjustment.second_pass_iterations = config.get_int(
      "bundle_adjustment.second_pass_iterations", m.bundle_adjustment.second_pass_iterations, 0, kMaxIterations);
  m.bundle_adjustment.disparity_sigma_ratio = config.get_double("bundle_adjustment.disparity_sigma_ratio",
                                                                m.bundle_adjustment.disparity_sigma_ratio, 0.01, 100.0);
  m.bundle_adjustment.num_threads =
      config.get_int("bundle_adjustment.threads", m.bundle_adjustment.num_threads, 1, kMaxThreads);
  m.enable_keyframe_culling = config.get_bool("keyframe_culling.enabled", m.enable_keyframe_culling);
  m.keyframe_culling.redundant_ratio =
      config.get_double("keyframe_culling.redundant_ratio", m.keyframe_culling.redundant_ratio, 0.0, 1.0);

  InertialMappingOptions& imu = o.inertial;
  imu.enabled = config.get_bool("imu.enabled", imu.enabled);
  imu.wait_s = config.get_double("imu.wait_s", imu.wait_s, 0.01, kMaxReaderWaitS);
  imu.window_keyframes = config.get_int("imu.window_keyframes", imu.window_keyframes, 1, kMaxNeighbours);
  imu.estimate_gravity = config.get_bool("imu.estimate_gravity", imu.estimate_gravity);
  imu.init_min_keyframes = config.get_int("imu.init_min_keyframes", imu.init_min_keyframes, 3, 1000);
  imu.init_min_duration_s = config.get_double("imu.init_min_duration_s", imu.init_min_duration_s, 0.1, 60.0);
  imu.init_max_keyframes = config.get_int("imu.init_max_keyframes", imu.init_max_keyframes, 3, 1000);
  imu.init.max_gravity_stddev_deg =
      config.get_double("imu.init_max_gravity_stddev_deg", imu.init.max_gravity_stddev_deg, 0.01, 90.0);
  imu.init.max_accel_bias_stddev_m_s2 =
      config.get_double("imu.init_max_accel_bias_stddev_m_s2", imu.init.max_accel_bias_stddev_m_s2, 0.001, 100.0);
  imu.init.max_gravity_stddev_of_prior =
      config.get_double("imu.init_max_gravity_stddev_of_prior", imu.init.max_gravity_stddev_of_prior, 0.01, 1000.0);
  imu.refine_every_s = config.get_double("imu.refine_every_s", imu.refine_every_s, 0.0, 3600.0);
  imu.refine_until_s = config.get_double("imu.refine_until_s", imu.refine_until_s, 0.0, 1e6);
  std::string imu_flag = "auto";

  runtime::Flags flags("heslam-local-mapper [options]");
  flags.path("--map-file", "FILE", &o.map_file, "the map file the mapper publishes from")
      .custom("--load-map", "FILE", "start from this saved map",
              [&o](const std::string& value) {
                o.load_map = value;
                o.load_map_given_empty = o.load_map.empty();
              })
      .path("--save-map", "FILE", &o.save_map, "save the map here at the end (\"\": none)")
      .toggle("--extend-map", &o.extend_map,
              "with --load-map: the final map replaces the loaded file at the end (unless --save-map FILE)")
      .integer("--agents", "N", &o.agents, 1, kMaxAgentId + 1,
               "frontends of agents 0..N-1 publish keyframes (docs/agents.md; 1: a single frontend)")
      .custom("--imu", "auto|none", "none: no inertial local BA whatever imu.enabled says (auto: imu.enabled)",
              [&imu_flag](const std::string& value) {
                if (value != "auto" && value != "none") runtime::throw_bad_flag_value("--imu", "auto or none", value);
                imu_flag = value;
              });
  flags.parse(rest);
  if (imu_flag == "none") imu.enabled = false;
  if (o.load_map_given_empty) {
    throw std::runtime_error(
        "--load-map: no saved map given (an empty file name; a localize or session pipeline needs "
        "--arg map=FILE, the map an earlier run saved)");
  }
  if (!o.load_map.empty() && !o.map_file.empty() &&
      std::filesystem::absolute(o.load_map).lexically_normal() ==
          std::filesystem::absolute(o.map_file).lexically_normal()) {
    // The run's working copy is replaced at the start of every run: the saved map would be deleted.
    throw std::runtime_error("--load-map " + o.load_map.string() +
                             ": is this run's own map file (--map-file, the pipelines' OUTPUT stem + .map), which a "
                             "run replaces; give the saved map another name or the run another output");
  }
  if (o.extend_map) {
    if (o.load_map.empty()) throw std::runtime_error("--extend-map: needs the saved map to extend (--load-map FILE)");
    if (o.save_map.empty()) o.save_map = o.load_map;
  }
  return o;
}

}  // namespace heslam::local_mapper
