// Config and command-line reading of the loop closer's options.
#include "components/loop_closer/loop_closer_options.hpp"

#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>

#include "components/core/map/ids.hpp"
#include "runtime/flags.hpp"

namespace heslam::loop_closer {
namespace {

// Bounds of the numeric options: wide enough for any sensible tuning, tight enough to reject typos.
constexpr int kMaxMatches = 100000;
constexpr double kMaxPixels = 200.0;
constexpr double kMaxTimeoutS = 3600.0;

}  // namespace

LoopCloserProcessOptions LoopCloserProcessOptions::from_config(const runtime::Config& config,
                                                               const std::vector<std::string>& rest) {
  LoopCloserProcessOptions o;
  LoopClosingOptions& c = o.closing;
  c.min_candidate_matches =
      config.get_int("verification.min_candidate_matches", c.min_candidate_matches, 3, kMaxMatches);
  c.min_ransac_inliers = config.get_int("verification.min_ransac_inliers", c.min_ransac_inliers, 3, kMaxMatches);
  c.min_loop_matches = config.get_int("verification.min_loop_matches", c.min_loop_matches, 3, kMaxMatches);
  c.projection_radius_px = static_cast<float>(
      config.get_double("verification.projection_radius_px", c.projection_radius_px, 0.5, kMaxPixels));
  c.max_drift_fraction = config.get_double("verification.max_drift_fraction", c.max_drift_fraction, 0.0, 10.0);
  c.min_drift_allowance_m = config.get_double("verification.min_drift_allowance_m", c.min_drift_allowance_m, 0.0, 1e6);
  c.max_rotation_drift_deg_per_m =
      config.get_double("verification.max_rotation_drift_deg_per_m", c.max_rotation_drift_deg_per_m, 0.0, 360.0);
  c.min_rotation_allowance_deg =
      config.get_double("verification.min_rotation_allowance_deg", c.min_rotation_allowance_deg, 0.0, 180.0);
  c.ransac_seed = static_cast<std::uint64_t>(
      config.get_int("verification.ransac_seed", static_cast<int>(c.ransac_seed), 0, INT_MAX));
  PoseGraphOptions& pose_graph = c.correction.pose_graph;
  pose_graph.four_dof = config.get_bool("pose_graph.four_dof", pose_graph.four_dof);
  const std::vector<double> gravity = config.get_doubles("pose_graph.gravity_w", {0.0, 0.0, -1.0});
  if (gravity.size() != 3 || !std::isfinite(gravity[0]) || !std::isfinite(gravity[1]) || !std::isfinite(gravity[2]) ||
      !(std::hypot(gravity[0], gravity[1], gravity[2]) > 0.0)) {
    throw std::runtime_error(config.source() + ": pose_graph.gravity_w: expected 3 finite numbers, not all 0 (" +
                             std::to_string(gravity.size()) + " given)");
  }
  pose_graph.gravity_w = Eigen::Vector3d(gravity[0], gravity[1], gravity[2]);
  o.gravity_from_odometry = config.get_bool("pose_graph.gravity_from_odometry", o.gravity_from_odometry);
  // The atlas's merges (docs/loop_closing.md, Merging).
  c.merging = config.get_bool("merge.enabled", c.merging);
  MapMergeOptions& merge = c.merge;
  merge.max_unobserved_speed_mps =
      config.get_double("merge.max_unobserved_speed_mps", merge.max_unobserved_speed_mps, 0.0, 1e6);
  merge.max_drift_fraction = config.get_double("merge.max_drift_fraction", merge.max_drift_fraction, 0.0, 10.0);
  merge.min_drift_allowance_m = config.get_double("merge.min_drift_allowance_m", merge.min_drift_allowance_m, 0.0, 1e6);
  merge.max_tilt_deg = config.get_double("merge.max_tilt_deg", merge.max_tilt_deg, 0.0, 180.0);
  merge.min_matches = config.get_int("merge.min_matches", merge.min_matches, 1, 100000);
  merge.covisible_confirmations = config.get_int("merge.covisible_confirmations", merge.covisible_confirmations, 0, 5);
  merge.confirmation_matches = config.get_int("merge.confirmation_matches", merge.confirmation_matches, 1, 100000);
  merge.min_found_share = config.get_double("merge.min_found_share", merge.min_found_share, 0.0, 1.0);
  merge.seam_bundle_adjustment = config.get_bool("merge.seam_bundle_adjustment", merge.seam_bundle_adjustment);
  o.global_bundle_adjustment = config.get_bool("global_ba.enabled", o.global_bundle_adjustment);
  o.global_ba_imu = config.get_bool("global_ba.imu", o.global_ba_imu);
  o.imu_buffer_s = config.get_double("global_ba.imu_buffer_s", o.imu_buffer_s, 1.0, 1e6);
  o.imu_wait_s = config.get_double("global_ba.imu_wait_s", o.imu_wait_s, 0.0, kMaxTimeoutS);
  o.imu_max_interval_s = config.get_double("global_ba.imu_max_interval_s", o.imu_max_interval_s, 0.01, 60.0);
  o.real_time = config.get_bool("real_time", o.real_time);
  const double timeout_s = config.get_double("lockstep.mapper_timeout_s", 30.0, 0.1, kMaxTimeoutS);
  o.mapper_timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  if (!config.get_string("state_file", "").empty()) o.state_file = config.get_path("state_file", {});
  if (!config.get_string("vocabulary.file", "").empty()) o.vocabulary = config.get_path("vocabulary.file", {});
  runtime::Flags flags("heslam-loop-closer [options]");
  flags.path("--state-file", "FILE", &o.state_file, "where the loop closer keeps its state (state_file)")
      .path("--vocabulary", "FILE", &o.vocabulary, "the BoW vocabulary (vocabulary.file)")
      .path("--mapper-map-file", "FILE", &o.mapper_map_file,
            "the local mapper's map file: a map it loaded is taken from there at start")
      .toggle("--real-time", &o.real_time, "do not wait for the mapper (real_time)")
      .integer("--agents", "N", &o.agents, 1, kMaxAgentId + 1,
               "frontends of agents 0..N-1 publish keyframes (docs/agents.md; 1: a single frontend)");
  flags.parse(rest);
  return o;
}

}  // namespace heslam::loop_closer
