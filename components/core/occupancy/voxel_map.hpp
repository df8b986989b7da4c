// A 3D log-odds occupancy map on a regular voxel lattice (OctoMap's sensor model without the octree):
// a depth point makes its voxel more likely occupied, the voxels its ray crossed from the camera more
// likely free. Voxel (i, j, k) is the cube [i, i+1) x [j, j+1) x [k, k+1) times resolution_m, so the
// lattice is fixed by the frame (two maps of one frame share their cells).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace heslam {

// How depth images are fused. kLogOdds: OctoMap's sensor model (each point a hit in its voxel, misses
// along its ray). kTsdf: a truncated signed distance per voxel (voxblox / KinectFusion): each voxel
// near a point takes the point's distance along the ray (positive in front), averaged over the images
// with weights 1 / sigma^2, so that the noise of stereo depth averages out where a hit per voxel
// spreads it into a fringe several voxels thick; a voxel is occupied where the averaged distance is
// within tsdf_occupied_m of zero, free where it is beyond the truncation in front.
enum class FusionModel { kLogOdds, kTsdf };
FusionModel parse_fusion_model(const std::string& name);  // "log_odds" | "tsdf"; throws std::invalid_argument
const char* to_string(FusionModel model);

struct VoxelMapOptions {
  double resolution_m = 0.05;
  FusionModel model = FusionModel::kLogOdds;
  // kTsdf: the band (metres along the ray) around each point whose voxels take its signed distance
  // (at least free_sigmas sigmas of the point); a voxel crossed farther in front is free space.
  double tsdf_truncation_m = 0.1;
  // kTsdf: occupied when |distance| <= this and the weight >= tsdf_min_weight (one exact observation
  // weighs 1, a point of sigma s (cell / s)^2 when s > a cell); free when the distance is at the truncation.
  double tsdf_occupied_m = 0.03;
  double tsdf_min_weight = 1.0;
  // kTsdf: free space (the images whose rays crossed a voxel in front of every band) is counted apart
  // from the distance, so rays passing a surface at a grazing angle never shift its distance; a voxel
  // is free when crossed in more than tsdf_free_ratio times its band weight (or its distance is in
  // front by half the truncation), and never occupied then.
  double tsdf_free_ratio = 4.0;
  // kTsdf: occupied only where the surface is (the zero crossing): a voxel within tsdf_occupied_m with
  // tsdf_min_weight whose distance is the smaller of a pair of 6-neighbours of opposite signs (both
  // with tsdf_min_weight), so that a wall along the lattice is one voxel thick wherever it lies
  // between the voxel centres. false: every voxel within tsdf_occupied_m of the surface (1-2 voxels).
  bool tsdf_zero_crossing = false;
  // kTsdf: a voxel's state is judged by the distance at its centre of a linear function (a plane's
  // signed distance) fitted by weighted least squares to the averaged distances of the (2 r + 1)^3
  // voxels around it that hold one within the truncation (at least 8 of them, not all on one plane;
  // else its own), and by the weight those voxels pool (for tsdf_min_weight and tsdf_free_ratio).
  // On a plane the fit is exact whichever neighbours were observed (a mean would lean towards the
  // side seen more), so only the noise averages out. 0: each voxel's own average (voxblox's).
  int tsdf_fit_radius = 0;
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
  // Depth uncertainty (per point sigma along the ray, integrate's `sigmas_m`): a point is a hit only
  // where its sigma is at most hit_max_sigma_m (about a cell: farther, stereo cannot place it in one
  // voxel and its hits spread into a fringe), and its ray is free only up to free_sigmas sigmas
  // before it (or free_margin_m, the larger). Points without a sigma are exact.
  double hit_max_sigma_m = 0.05;
  double free_sigmas = 2.0;
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
  // points beyond max_ray_m are skipped; returns how many points were used. `sigmas_m`: each point's
  // depth sigma along its ray (empty: exact points; see hit_max_sigma_m).
  // `normals`: each point's surface normal (zero: unknown; empty: none), used by kTsdf only.
  std::size_t integrate(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3f> points,
                        std::span<const float> sigmas_m = {}, std::span<const Eigen::Vector3f> normals = {});

  // The voxels a segment from a to b crosses, in order, both ends' voxels included (Amanatides-Woo).
  // `visit` returns false to stop early.
  void traverse(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                const std::function<bool(const VoxelIndex&)>& visit) const;

  // Log-odds of a voxel (kLogOdds; the signed distance with kTsdf); 0 when never observed.
  float log_odds(const VoxelIndex& v) const;
  // kTsdf: the voxel's averaged signed distance and weight (0 when never observed).
  float sdf(const VoxelIndex& v) const { return log_odds(v); }
  float weight(const VoxelIndex& v) const;
  float crossed(const VoxelIndex& v) const { return cell(v).crossed; }
  bool observed(const VoxelIndex& v) const;
  bool occupied(const VoxelIndex& v) const { return state_at(v, cell(v)) == VoxelState::kOccupied; }
  bool free(const VoxelIndex& v) const { return state_at(v, cell(v)) == VoxelState::kFree; }

  // kNear (kTsdf only): observed near a surface, not confirmed occupied; a grid column holding one is
  // never called free.
  enum class VoxelState : std::uint8_t { kUnknown, kFree, kOccupied, kNear };
  // Every observed voxel and its state (unordered); with min_layer / max_layer only the voxels whose z
  // index lies in that range (a grid's band: with tsdf_fit_radius the fit is made for those alone).
  void for_each_state(const std::function<void(const VoxelIndex&, VoxelState)>& visit,
                      int min_layer = std::numeric_limits<int>::min(),
                      int max_layer = std::numeric_limits<int>::max()) const;

  std::size_t size() const { return cells_.size(); }
  void clear() { cells_.clear(); }
  // Every observed voxel and its log-odds (or signed distance; unordered).
  void for_each(const std::function<void(const VoxelIndex&, float)>& visit) const;
  // Bytes held by the cells (the hash table's nodes and buckets), for the memory figure.
  std::size_t memory_bytes() const;

 private:
  // kLogOdds: value = log-odds, weight unused; kTsdf: value = signed distance (m), weight = sum of weights.
  struct Cell {
    float value = 0.f;
    float weight = 0.f;
    float crossed = 0.f;  // kTsdf: images whose rays crossed the voxel in front of their bands
  };
  static std::uint64_t key(const VoxelIndex& v);
  static VoxelIndex unkey(std::uint64_t key);
  void update(std::uint64_t key, float delta);
  Cell cell(const VoxelIndex& v) const;
  // `evidence`: the weight the min-weight and free-ratio tests use (the cell's own, or its fit's pooled weight).
  VoxelState state(const Cell& c, float evidence) const;
  VoxelState state(const Cell& c) const { return state(c, c.weight); }
  // A tsdf_fit_radius fit: the distance at the voxel's centre and the weight of the voxels it pooled.
  struct Fit {
    float distance;
    float weight;
  };
  // state() with the zero-crossing rule (tsdf_zero_crossing), which needs the voxel's neighbours.
  // `fitted`: the tsdf_fit_radius distances by key (a voxel absent keeps its own), or null.
  VoxelState state_at(const VoxelIndex& v, const Cell& c,
                      const std::unordered_map<std::uint64_t, Fit>* fitted = nullptr) const;
  // The tsdf_fit_radius distance of every voxel with z index in [min_layer, max_layer] that holds one.
  std::unordered_map<std::uint64_t, Fit> fitted_distances(int min_layer, int max_layer) const;
  std::size_t integrate_tsdf(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3f> points,
                             std::span<const float> sigmas_m, std::span<const Eigen::Vector3f> normals);

  VoxelMapOptions options_;
  std::unordered_map<std::uint64_t, Cell> cells_;
};

}  // namespace heslam
