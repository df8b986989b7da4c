// A 3D log-odds occupancy map on a regular voxel lattice (OctoMap's sensor model without the octree):
// a depth point makes its voxel more likely occupied, the voxels its ray crossed from the camera more
// likely free. Voxel (i, j, k) is the cube [i, i+1) x [j, j+1) x [k, k+1) times resolution_m, so the
// lattice is fixed by the frame (two maps of one frame share their cells).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace heslam {

struct VoxelMapOptions {
  double resolution_m = 0.05;
  // Log-odds of one observation and the clamping bounds: OctoMap's defaults (hit 0.7, miss 0.4,
  // clamped to [0.12, 0.97]), so a cell flips after a few contrary observations, never after one.
  float hit_log_odds = 0.847f;
  float miss_log_odds = -0.405f;
  float min_log_odds = -1.992f;
  float max_log_odds = 3.476f;
  // A voxel is occupied above this log-odds (p > 0.5) and free below -this.
  float occupied_log_odds = 0.0f;
  // Free space ends this far before each point: the voxels a ray crosses just before its hit often
  // hold the same surface (a ray at a grazing angle runs through the surface's voxel layer for
  // resolution / sin(angle)), and marking them free carves the surface away. 0: OctoMap's rays.
  double free_margin_m = 0.2;
  // Points farther than this from the ray's origin are not used (a bound on the work per point).
  double max_ray_m = 50.0;
};

struct VoxelIndex {
  int x = 0;
  int y = 0;
  int z = 0;
  bool operator==(const VoxelIndex&) const = default;
};

class VoxelMap {
 public:
  // Throws std::invalid_argument when resolution_m is not positive and finite or the log-odds are
  // inconsistent (hit <= 0, miss >= 0, min >= max).
  explicit VoxelMap(const VoxelMapOptions& options = {});

  const VoxelMapOptions& options() const { return options_; }

  VoxelIndex index_of(const Eigen::Vector3d& p) const;
  Eigen::Vector3d center_of(const VoxelIndex& v) const;

  // One depth image's points (the same frame as the map) seen from `origin`: every voxel a ray from
  // the origin to a point crosses is updated once as a miss, every voxel holding a point once as a hit
  // (a voxel both crossed and hit counts as hit only: OctoMap's computeUpdate). Non-finite points and
  // points beyond max_ray_m are skipped; returns how many points were used.
  std::size_t integrate(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3f> points);

  // The voxels a segment from a to b crosses, in order, both ends' voxels included (Amanatides-Woo).
  // `visit` returns false to stop early.
  void traverse(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                const std::function<bool(const VoxelIndex&)>& visit) const;

  // Log-odds of a voxel; 0 (unknown) when never observed.
  float log_odds(const VoxelIndex& v) const;
  bool observed(const VoxelIndex& v) const;
  bool occupied(const VoxelIndex& v) const { return log_odds(v) > options_.occupied_log_odds; }
  bool free(const VoxelIndex& v) const { return observed(v) && log_odds(v) < -options_.occupied_log_odds; }

  std::size_t size() const { return cells_.size(); }
  void clear() { cells_.clear(); }
  // Every observed voxel and its log-odds (unordered).
  void for_each(const std::function<void(const VoxelIndex&, float)>& visit) const;
  // Bytes held by the cells (the hash table's nodes and buckets), for the memory figure.
  std::size_t memory_bytes() const;

 private:
  static std::uint64_t key(const VoxelIndex& v);
  static VoxelIndex unkey(std::uint64_t key);
  void update(std::uint64_t key, float delta);

  VoxelMapOptions options_;
  std::unordered_map<std::uint64_t, float> cells_;
};

}  // namespace heslam
