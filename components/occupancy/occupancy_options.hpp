// Options of heslam-occupancy: the config file's fields (config/occupancy/*.yaml, docs/occupancy.md)
// and its command line.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "components/core/image/histogram_equalizer.hpp"
#include "components/core/occupancy/dense_stereo.hpp"
#include "components/core/occupancy/multiview_depth.hpp"
#include "components/core/occupancy/occupancy_map.hpp"
#include "runtime/config.hpp"

namespace heslam::occupancy {

struct OccupancyProcessOptions {
  DenseStereoOptions stereo;  // stereo.*
  // multiview.*: each keyframe's disparity refined against the previous keyframes' left images
  // (MultiViewDepth; neighbours 0: off).
  MultiViewDepthOptions multiview;
  OccupancyMapOptions map;  // voxel.*, grid.*
  // HE.* of the settings file the frontend reads (settings.file / --settings FILE): the dense
  // matcher sees the images as the frontend's ORB does, so it works where HE-SLAM works.
  std::filesystem::path settings_file;
  HistogramEqualizerOptions he;
  // frame_ring: raw frames kept by stamp for the keyframes still to come (the keyframe of a frame is
  // published after it, by another process).
  int frame_ring = 30;
  // rebuild_period_s: a map made stale by moved keyframes is fused again at most this often while
  // running and idle (always at the end).
  double rebuild_period_s = 10.0;
  // live.*: the grid (map/occupancy_grid) is published when it changed, at most every grid_period_s
  // (0: at every change); the dense cloud (map/dense_cloud) at most every cloud_period_s, decimated to
  // cloud_max_points (0: no cloud topic). Both once more, final, at the end.
  double grid_period_s = 2.0;
  double cloud_period_s = 10.0;
  int cloud_max_points = 200000;
  // idle_priority: the worker thread (disparity, fusion) runs as SCHED_IDLE, i.e. only on CPU time no
  // other thread wants, so on a loaded machine it never takes the frontend's: the real-time pipelines
  // (config/occupancy/real_time.yaml). It may fall behind instead; frames wait in its queue, none is lost.
  bool idle_priority = false;
  // first_poses_grid: also STEM.first_poses.pgm + .yaml at the end: every cloud fused at its keyframe's
  // first pose (the frontend's, before the mapper's refinement and any loop correction), the map as if
  // no correction had come, beside the corrected one (docs/occupancy.md, "A loop correction").
  bool first_poses_grid = false;
  // grid.up_from_gravity: once the odometry carries a gravity (an inertial run, docs/imu.md), the grid's
  // up is against it instead of grid.up's axis (the map is fused again then), so the height band is level
  // and the grid lies in the gravity-aligned map the recorder and the ROS 2 bridge use. Stereo-only
  // runs carry no gravity: unchanged.
  bool up_from_gravity = true;
  // --output-stem STEM: STEM.pgm, STEM.yaml (map_server), STEM.ply written at the end; empty: none.
  std::filesystem::path output_stem;
  // --state-dir DIR: one file per keyframe cloud (replaced atomically), so a restarted process
  // rebuilds its map without the frames it can no longer see; empty: nothing persisted.
  std::filesystem::path state_dir;

  // Throws std::runtime_error (one line: file, field, expectation) on a bad field or argument.
  static OccupancyProcessOptions from_config(const runtime::Config& config, const std::vector<std::string>& rest);
};

}  // namespace heslam::occupancy
