// The occupancy map of a run: one dense cloud per keyframe, kept in the keyframe's camera frame, and
// fused into a VoxelMap at the keyframes' current poses. A refined pose or a loop correction moves a
// keyframe's cloud with it (the fused map is rebuilt), a culled keyframe's cloud leaves the map.
//
// Frames: clouds are in their keyframe's camera frame; poses are T_wc in the SLAM world frame; the
// voxel map and the grid are in the "grid frame", the world turned so that `up` is its z axis (the
// first camera's -y without an IMU: x right, y down, z forward is the world then).
//
// Determinism: rebuild() fuses the clouds in keyframe id order, so the same clouds at the same poses
// give the same voxels and grid whatever the order the keyframes, poses and clouds arrived in.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "components/core/occupancy/voxel_map.hpp"

namespace heslam {

// Which world axis points up: "-y" (the first camera's up, the SLAM world without an IMU), "y" or "z"
// (a gravity-aligned world, z up).
enum class UpAxis { kMinusY, kY, kZ };
UpAxis parse_up_axis(const std::string& name);  // throws std::invalid_argument
const char* to_string(UpAxis up);
// The axis as a world direction: -y is (0, -1, 0).
Eigen::Vector3d up_direction(UpAxis up);

struct OccupancyMapOptions {
  VoxelMapOptions voxels;
  GridBand band;
  UpAxis up = UpAxis::kMinusY;
  // A fused keyframe whose pose moved more than this since it was fused makes the map stale (rebuilt
  // by rebuild_if_stale): below it, a move is within a voxel's quantization.
  double stale_translation_m = 0.01;
  double stale_rotation_rad = 0.005;
};

struct KeyframeCloud {
  std::int64_t stamp_ns = 0;
  std::vector<Eigen::Vector3f> points_c;  // keyframe camera frame, metres
  // Stereo depth uncertainty: sigma_d / bf (1/m, sigma_d the disparity sigma in pixels), so that a point
  // at depth z and range r has a sigma along its ray of r * z * this (z^2 / bf * sigma_d in depth).
  // 0: exact points (true depth).
  float sigma_per_m2 = 0.f;
  // Per point, the surface normal (keyframe camera frame, towards the camera; zero: unknown), or empty.
  // kTsdf fusion measures a voxel's distance to the point's plane instead of along the ray, so that a
  // surface seen at a grazing angle is not pushed a few voxels off itself.
  std::vector<Eigen::Vector3f> normals_c;
};

class OccupancyMap {
 public:
  explicit OccupancyMap(const OccupancyMapOptions& options = {});

  const OccupancyMapOptions& options() const { return options_; }

  // The keyframe's current pose (its first from the frontend, then the mapper's). Returns false (and
  // changes nothing) for a non-finite pose.
  bool set_pose(std::uint64_t id, const Pose3& T_wc);
  // A keyframe the mapper culled: its cloud leaves the map and never comes back.
  void cull(std::uint64_t id);
  bool culled(std::uint64_t id) const { return culled_.count(id) != 0; }
  // The dense cloud of a keyframe; fused at once when its pose is known.
  void add_cloud(std::uint64_t id, KeyframeCloud cloud);
  bool has_cloud(std::uint64_t id) const { return clouds_.count(id) != 0; }
  bool has_pose(std::uint64_t id) const { return poses_.count(id) != 0; }

  // Fuses clouds whose pose arrived since (incremental).
  void fuse_pending();
  // Whether a fused keyframe moved (stale thresholds) or left since it was fused.
  bool stale() const { return stale_; }
  // Fuses every cloud again at the current poses, in id order (see the header comment).
  void rebuild();
  void rebuild_if_stale() {
    if (stale_) rebuild();
  }

  const VoxelMap& voxels() const { return voxels_; }
  OccupancyGrid grid() const { return OccupancyGrid::from_voxels(voxels_, options_.band); }
  // world -> grid frame rotation.
  const Eigen::Matrix3d& R_gw() const { return R_gw_; }
  // The grid's up as a world direction (against gravity, from the IMU): the grid frame becomes the
  // `up` option's turned by the smallest rotation that takes this direction to its z, so heights are
  // along it and the grid is level. The voxels were fused in the old frame: they are dropped, and the
  // next fuse_pending() (or rebuild()) fuses every cloud again. Returns false, changing nothing, for a
  // direction that is not finite or not of unit length (1 +- 1e-6).
  bool set_up_direction(const Eigen::Vector3d& up_w);
  // The angle (radians) between a world direction (unit length) and the grid's current up.
  double angle_to_up(const Eigen::Vector3d& up_w) const;

  std::size_t clouds() const { return clouds_.size(); }
  std::size_t fused() const { return fused_.size(); }
  std::size_t cloud_points() const;
  const std::map<std::uint64_t, KeyframeCloud>& all_clouds() const { return clouds_; }
  const std::map<std::uint64_t, Pose3>& poses() const { return poses_; }  // T_wc of every keyframe known

  // Every fused cloud point in the world frame, as a binary little-endian PLY (x y z float), replaced
  // atomically. Returns the points written. Throws std::runtime_error naming the file.
  std::size_t write_ply(const std::filesystem::path& file) const;

 private:
  void fuse(std::uint64_t id, const KeyframeCloud& cloud, const Pose3& T_wc);

  OccupancyMapOptions options_;
  Eigen::Matrix3d R_gw_;
  VoxelMap voxels_;
  std::map<std::uint64_t, Pose3> poses_;
  std::map<std::uint64_t, KeyframeCloud> clouds_;
  std::map<std::uint64_t, Pose3> fused_;  // the pose each fused cloud was fused at
  std::map<std::uint64_t, bool> culled_;
  bool stale_ = false;
};

// A keyframe cloud as a file (binary: magic HESOCC02, id, stamp, count, sigma_per_m2 float, a
// normals flag uint32, x y z float per point, then the normals' x y z when flagged), replaced
// atomically; read back exactly. read_cloud throws std::runtime_error naming the file on a short or
// foreign file.
void write_cloud(const std::filesystem::path& file, std::uint64_t id, const KeyframeCloud& cloud);
KeyframeCloud read_cloud(const std::filesystem::path& file, std::uint64_t& id);

}  // namespace heslam
