// The log-odds voxel map (see voxel_map.hpp).
#include "components/core/occupancy/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace heslam {
namespace {

// 21 bits per axis: +-2^20 voxels, +-52 km at 5 cm.
constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << kAxisBits) - 1;

}  // namespace

VoxelMap::VoxelMap(const VoxelMapOptions& options) : options_(options) {
  if (!(options.resolution_m > 0.0) || !std::isfinite(options.resolution_m)) {
    throw std::invalid_argument("voxel map: resolution_m must be a positive number");
  }
  if (!(options.hit_log_odds > 0.f) || !(options.miss_log_odds < 0.f) ||
      !(options.min_log_odds < options.max_log_odds)) {
    throw std::invalid_argument("voxel map: log-odds need hit > 0 > miss and min < max");
  }
}

VoxelIndex VoxelMap::index_of(const Eigen::Vector3d& p) const {
  const double r = options_.resolution_m;
  return {static_cast<int>(std::floor(p.x() / r)), static_cast<int>(std::floor(p.y() / r)),
          static_cast<int>(std::floor(p.z() / r))};
}

Eigen::Vector3d VoxelMap::center_of(const VoxelIndex& v) const {
  const double r = options_.resolution_m;
  return {(v.x + 0.5) * r, (v.y + 0.5) * r, (v.z + 0.5) * r};
}

std::uint64_t VoxelMap::key(const VoxelIndex& v) {
  auto axis = [](int value) { return static_cast<std::uint64_t>(value + kAxisOffset) & kAxisMask; };
  return axis(v.x) | (axis(v.y) << kAxisBits) | (axis(v.z) << (2 * kAxisBits));
}

VoxelIndex VoxelMap::unkey(std::uint64_t key) {
  auto axis = [&](int shift) {
    return static_cast<int>(static_cast<std::int64_t>((key >> shift) & kAxisMask) - kAxisOffset);
  };
  return {axis(0), axis(kAxisBits), axis(2 * kAxisBits)};
}

void VoxelMap::update(std::uint64_t k, float delta) {
  float& value = cells_[k];
  value = std::clamp(value + delta, options_.min_log_odds, options_.max_log_odds);
}

float VoxelMap::log_odds(const VoxelIndex& v) const {
  const auto found = cells_.find(key(v));
  return found == cells_.end() ? 0.f : found->second;
}

bool VoxelMap::observed(const VoxelIndex& v) const { return cells_.count(key(v)) != 0; }

namespace {

// Amanatides-Woo over voxels of side r from a to b; visit(x, y, z) returns false to stop.
template <typename Visit>
void walk(double r, const Eigen::Vector3d& a, const Eigen::Vector3d& b, Visit&& visit) {
  int cur[3] = {static_cast<int>(std::floor(a.x() / r)), static_cast<int>(std::floor(a.y() / r)),
                static_cast<int>(std::floor(a.z() / r))};
  const int end[3] = {static_cast<int>(std::floor(b.x() / r)), static_cast<int>(std::floor(b.y() / r)),
                      static_cast<int>(std::floor(b.z() / r))};
  if (!visit(cur[0], cur[1], cur[2])) return;
  const Eigen::Vector3d direction = b - a;
  int step[3];
  double t_max[3];
  double t_delta[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double d = direction[axis];
    if (d > 0.0) {
      step[axis] = 1;
      t_delta[axis] = r / d;
      t_max[axis] = ((cur[axis] + 1) * r - a[axis]) / d;
    } else if (d < 0.0) {
      step[axis] = -1;
      t_delta[axis] = -r / d;
      t_max[axis] = (cur[axis] * r - a[axis]) / d;
    } else {
      step[axis] = 0;
      t_delta[axis] = std::numeric_limits<double>::infinity();
      t_max[axis] = std::numeric_limits<double>::infinity();
    }
  }
  // At most the Manhattan distance in voxels: a guard against rounding at exact voxel boundaries.
  int remaining = std::abs(end[0] - cur[0]) + std::abs(end[1] - cur[1]) + std::abs(end[2] - cur[2]);
  while (remaining-- > 0) {
    int axis = 0;
    if (t_max[1] < t_max[axis]) axis = 1;
    if (t_max[2] < t_max[axis]) axis = 2;
    if (t_max[axis] > 1.0) break;  // rounding: b's voxel is visited below
    cur[axis] += step[axis];
    t_max[axis] += t_delta[axis];
    if (!visit(cur[0], cur[1], cur[2])) return;
    if (cur[0] == end[0] && cur[1] == end[1] && cur[2] == end[2]) return;
  }
  if (cur[0] != end[0] || cur[1] != end[1] || cur[2] != end[2]) visit(end[0], end[1], end[2]);
}

}  // namespace

void VoxelMap::traverse(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const std::function<bool(const VoxelIndex&)>& visit) const {
  walk(options_.resolution_m, a, b, [&](int x, int y, int z) { return visit({x, y, z}); });
}

std::size_t VoxelMap::integrate(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3f> points) {
  if (!origin.allFinite()) return 0;
  std::vector<std::uint64_t> hits;
  std::vector<std::uint64_t> misses;
  hits.reserve(points.size());
  std::size_t used = 0;
  for (const Eigen::Vector3f& point_f : points) {
    const Eigen::Vector3d point = point_f.cast<double>();
    if (!point.allFinite() || (point - origin).norm() > options_.max_ray_m) continue;
    ++used;
    const std::uint64_t end_key = key(index_of(point));
    hits.push_back(end_key);
    const double length = (point - origin).norm();
    if (length <= options_.free_margin_m) continue;
    const Eigen::Vector3d free_end = origin + (point - origin) * ((length - options_.free_margin_m) / length);
    walk(options_.resolution_m, origin, free_end, [&](int x, int y, int z) {
      const std::uint64_t k = key({x, y, z});
      if (k != end_key) misses.push_back(k);
      return true;
    });
  }
  // Each voxel once per image, a hit winning over a miss (sorted keys: the order of the updates
  // within an image does not matter, as each key is updated once).
  std::sort(hits.begin(), hits.end());
  hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
  std::sort(misses.begin(), misses.end());
  misses.erase(std::unique(misses.begin(), misses.end()), misses.end());
  auto hit = hits.begin();
  for (const std::uint64_t k : misses) {
    while (hit != hits.end() && *hit < k) ++hit;
    if (hit != hits.end() && *hit == k) continue;
    update(k, options_.miss_log_odds);
  }
  for (const std::uint64_t k : hits) update(k, options_.hit_log_odds);
  return used;
}

void VoxelMap::for_each(const std::function<void(const VoxelIndex&, float)>& visit) const {
  for (const auto& [k, value] : cells_) visit(unkey(k), value);
}

std::size_t VoxelMap::memory_bytes() const {
  // A node: next pointer, key, value (+ cached hash in libstdc++ only for non-fast hashes); a bucket pointer.
  return cells_.size() * (sizeof(void*) + sizeof(std::uint64_t) + sizeof(float) + 4) +
         cells_.bucket_count() * sizeof(void*);
}

}  // namespace heslam
