// Config and command-line reading of heslam-occupancy's options.
#include "components/occupancy/occupancy_options.hpp"

#include <stdexcept>

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "runtime/flags.hpp"

namespace heslam::occupancy {

OccupancyProcessOptions OccupancyProcessOptions::from_config(const runtime::Config& config,
                                                             const std::vector<std::string>& rest) {
  OccupancyProcessOptions o;
  DenseStereoOptions& s = o.stereo;
  s.num_disparities = config.get_int("stereo.num_disparities", s.num_disparities, 16, 512);
  s.block_size = config.get_int("stereo.block_size", s.block_size, 1, 11);
  s.uniqueness_ratio = config.get_int("stereo.uniqueness_ratio", s.uniqueness_ratio, 0, 100);
  s.speckle_window = config.get_int("stereo.speckle_window", s.speckle_window, 0, 10000);
  s.speckle_range = config.get_int("stereo.speckle_range", s.speckle_range, 0, 64);
  s.min_depth_m = config.get_double("stereo.min_depth_m", s.min_depth_m, 0.01, 1000.0);
  s.max_depth_m = config.get_double("stereo.max_depth_m", s.max_depth_m, 0.01, 1000.0);
  s.pixel_step = config.get_int("stereo.pixel_step", s.pixel_step, 1, 64);
  s.thin_voxel_m = config.get_double("stereo.thin_voxel_m", s.thin_voxel_m, 0.0, 10.0);
  s.disp12_max_diff = config.get_int("stereo.disp12_max_diff", s.disp12_max_diff, -1, 64);
  s.edge_radius_px = config.get_int("stereo.edge_radius_px", s.edge_radius_px, 0, 16);
  s.edge_step_px = config.get_double("stereo.edge_step_px", s.edge_step_px, 0.01, 64.0);
  s.smooth_radius_px = config.get_int("stereo.smooth_radius_px", s.smooth_radius_px, 0, 16);
  s.refine_iterations = config.get_int("stereo.refine_iterations", s.refine_iterations, 0, 32);
  s.refine_radius_px = config.get_int("stereo.refine_radius_px", s.refine_radius_px, 1, 16);
  s.refine_max_change_px = config.get_double("stereo.refine_max_change_px", s.refine_max_change_px, 0.01, 16.0);
  s.refine_prefilter_sigma_px =
      config.get_double("stereo.refine_prefilter_sigma_px", s.refine_prefilter_sigma_px, 0.0, 8.0);
  s.disparity_sigma_px = config.get_double("stereo.disparity_sigma_px", s.disparity_sigma_px, 0.0, 16.0);
  s.check(config.source() + ": stereo");
  MultiViewDepthOptions& m = o.multiview;
  m.neighbours = config.get_int("multiview.neighbours", m.neighbours, 0, 8);
  m.min_baseline_ratio = config.get_double("multiview.min_baseline_ratio", m.min_baseline_ratio, 0.0, 1000.0);
  m.max_baseline_m = config.get_double("multiview.max_baseline_m", m.max_baseline_m, 0.001, 1000.0);
  m.search_range_px = config.get_double("multiview.search_range_px", m.search_range_px, 0.01, 8.0);
  m.step_px = config.get_double("multiview.step_px", m.step_px, 0.01, 4.0);
  m.max_candidates = config.get_int("multiview.max_candidates", m.max_candidates, 3, 129);
  m.patch_radius_px = config.get_int("multiview.patch_radius_px", m.patch_radius_px, 1, 8);
  m.prefilter_sigma_px = config.get_double("multiview.prefilter_sigma_px", m.prefilter_sigma_px, 0.0, 8.0);
  m.level = config.get_int("multiview.level", m.level, 0, 2);
  m.passes = config.get_int("multiview.passes", m.passes, 1, 4);
  m.pass_range_factor = config.get_double("multiview.pass_range_factor", m.pass_range_factor, 0.01, 1.0);
  m.base_radius_px = config.get_int("multiview.base_radius_px", m.base_radius_px, 0, 16);
  m.base_step_px = config.get_double("multiview.base_step_px", m.base_step_px, 0.01, 64.0);
  m.min_zncc = config.get_double("multiview.min_zncc", m.min_zncc, -1.0, 1.0);
  m.use_right = config.get_bool("multiview.use_right", m.use_right);
  m.keep_unrefined = config.get_bool("multiview.keep_unrefined", m.keep_unrefined);
  m.check(config.source() + ": multiview");
  VoxelMapOptions& v = o.map.voxels;
  v.resolution_m = config.get_double("voxel.resolution_m", v.resolution_m, 0.005, 10.0);
  v.model = parse_fusion_model(config.get_choice("voxel.model", to_string(v.model), {"log_odds", "tsdf"}));
  v.free_margin_m = config.get_double("voxel.free_margin_m", v.free_margin_m, 0.0, 10.0);
  v.hit_max_sigma_m = config.get_double("voxel.hit_max_sigma_m", v.hit_max_sigma_m, 0.0, 100.0);
  v.free_sigmas = config.get_double("voxel.free_sigmas", v.free_sigmas, 0.0, 100.0);
  v.tsdf_truncation_m = config.get_double("voxel.tsdf_truncation_m", v.tsdf_truncation_m, 0.001, 10.0);
  v.tsdf_occupied_m = config.get_double("voxel.tsdf_occupied_m", v.tsdf_occupied_m, 0.001, 10.0);
  v.tsdf_min_weight = config.get_double("voxel.tsdf_min_weight", v.tsdf_min_weight, 0.001, 1e6);
  v.tsdf_free_ratio = config.get_double("voxel.tsdf_free_ratio", v.tsdf_free_ratio, 0.001, 1e6);
  v.tsdf_zero_crossing = config.get_bool("voxel.tsdf_zero_crossing", v.tsdf_zero_crossing);
  v.tsdf_fit_radius = config.get_int("voxel.tsdf_fit_radius", v.tsdf_fit_radius, 0, 3);
  if (!(v.tsdf_occupied_m < v.tsdf_truncation_m)) {
    throw std::runtime_error(config.source() + ": voxel.tsdf_occupied_m must be below voxel.tsdf_truncation_m");
  }
  o.map.band.min_m = config.get_double("grid.band_min_m", o.map.band.min_m, -1000.0, 1000.0);
  o.map.band.max_m = config.get_double("grid.band_max_m", o.map.band.max_m, -1000.0, 1000.0);
  if (!(o.map.band.min_m < o.map.band.max_m)) {
    throw std::runtime_error(config.source() + ": grid.band_min_m must be below grid.band_max_m");
  }
  o.map.up = parse_up_axis(config.get_choice("grid.up", "-y", {"-y", "y", "z"}));
  o.frame_ring = config.get_int("frame_ring", o.frame_ring, 1, 1000);
  o.rebuild_period_s = config.get_double("rebuild_period_s", o.rebuild_period_s, 0.0, 3600.0);
  o.grid_period_s = config.get_double("live.grid_period_s", o.grid_period_s, 0.0, 3600.0);
  o.cloud_period_s = config.get_double("live.cloud_period_s", o.cloud_period_s, 0.0, 3600.0);
  o.cloud_max_points = config.get_int("live.cloud_max_points", o.cloud_max_points, 0, 10000000);
  o.idle_priority = config.get_bool("idle_priority", o.idle_priority);
  o.first_poses_grid = config.get_bool("first_poses_grid", o.first_poses_grid);
  o.up_from_gravity = config.get_bool("grid.up_from_gravity", o.up_from_gravity);
  if (!config.get_string("settings.file", "").empty()) o.settings_file = config.get_path("settings.file", {});
  std::filesystem::path settings_arg;
  runtime::Flags flags("heslam-occupancy [options]");
  flags.path("--settings", "FILE", &settings_arg, "the frontend's settings file, for its HE.* (empty: settings.file)")
      .path("--output-stem", "STEM", &o.output_stem, "STEM.pgm / STEM.yaml (map_server) and STEM.ply at the end")
      .path("--state-dir", "DIR", &o.state_dir, "keyframe clouds kept for a restart (empty: none)");
  flags.parse(rest);
  if (!settings_arg.empty()) o.settings_file = settings_arg;
  if (!o.settings_file.empty()) o.he = StereoFeaturePipelineOptions::load(o.settings_file).he;
  return o;
}

}  // namespace heslam::occupancy
