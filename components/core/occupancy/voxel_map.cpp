// The log-odds voxel map (see voxel_map.hpp).
#include "components/core/occupancy/voxel_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>

namespace heslam {
namespace {

// 21 bits per axis: +-2^20 voxels, +-52 km at 5 cm.
constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisOffset = std::int64_t{1} << (kAxisBits - 1);
constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << kAxisBits) - 1;

}  // namespace

FusionModel parse_fusion_model(const std::string& name) {
  if (name == "log_odds") return FusionModel::kLogOdds;
  if (name == "tsdf") return FusionModel::kTsdf;
  throw std::invalid_argument("fusion model '" + name + "': expected log_odds or tsdf");
}

const char* to_string(FusionModel model) { return model == FusionModel::kTsdf ? "tsdf" : "log_odds"; }

VoxelMap::VoxelMap(const VoxelMapOptions& options) : options_(options) {
  if (!(options.resolution_m > 0.0) || !std::isfinite(options.resolution_m)) {
    throw std::invalid_argument("voxel map: resolution_m must be a positive number");
  }
  if (!(options.hit_log_odds > 0.f) || !(options.miss_log_odds < 0.f) ||
      !(options.min_log_odds < options.max_log_odds)) {
    throw std::invalid_argument("voxel map: log-odds need hit > 0 > miss and min < max");
  }
  if (!(options.tsdf_truncation_m > 0.0) || !(options.tsdf_occupied_m > 0.0) ||
      !(options.tsdf_occupied_m < options.tsdf_truncation_m) || !(options.tsdf_min_weight > 0.0) ||
      !(options.tsdf_free_ratio > 0.0)) {
    throw std::invalid_argument("voxel map: tsdf needs 0 < occupied_m < truncation_m, min_weight > 0, free_ratio > 0");
  }
  if (options.tsdf_fit_radius < 0 || options.tsdf_fit_radius > 3) {
    throw std::invalid_argument("voxel map: tsdf_fit_radius must be 0..3 voxels");
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
  float& value = cells_[k].value;
  value = std::clamp(value + delta, options_.min_log_odds, options_.max_log_odds);
}

VoxelMap::Cell VoxelMap::cell(const VoxelIndex& v) const {
  const auto found = cells_.find(key(v));
  return found == cells_.end() ? Cell{} : found->second;
}

float VoxelMap::log_odds(const VoxelIndex& v) const { return cell(v).value; }

float VoxelMap::weight(const VoxelIndex& v) const { return cell(v).weight; }

VoxelMap::VoxelState VoxelMap::state(const Cell& c, float evidence) const {
  if (options_.model == FusionModel::kTsdf) {
    const double crossed_limit = options_.tsdf_free_ratio * evidence;
    if (c.crossed > crossed_limit) return VoxelState::kFree;
    if (!(c.weight > 0.f)) return VoxelState::kUnknown;
    if (std::abs(c.value) <= options_.tsdf_occupied_m && evidence >= options_.tsdf_min_weight) {
      return VoxelState::kOccupied;
    }
    // Free: the band's averaged distance is in front by more than half the truncation.
    if (c.value >= 0.5 * options_.tsdf_truncation_m && evidence >= options_.tsdf_min_weight) return VoxelState::kFree;
    return std::abs(c.value) < 0.5 * options_.tsdf_truncation_m ? VoxelState::kNear : VoxelState::kUnknown;
  }
  if (c.value > options_.occupied_log_odds) return VoxelState::kOccupied;
  if (c.value < -options_.occupied_log_odds) return VoxelState::kFree;
  return VoxelState::kUnknown;
}

VoxelMap::VoxelState VoxelMap::state_at(const VoxelIndex& v, const Cell& own,
                                        const std::unordered_map<std::uint64_t, Fit>* fitted) const {
  // A cell's distance and evidence: its fit's where it has one, else its own.
  const auto judged = [&](std::uint64_t k, Cell c) {
    float evidence = c.weight;
    if (fitted) {
      if (const auto found = fitted->find(k); found != fitted->end()) {
        c.value = found->second.distance;
        evidence = found->second.weight;
      }
    }
    return std::pair{c, evidence};
  };
  const auto [c, evidence] = judged(key(v), own);
  const VoxelState s = state(c, evidence);
  if (options_.model != FusionModel::kTsdf || !options_.tsdf_zero_crossing || s != VoxelState::kOccupied) return s;
  // Occupied only when the surface lies between this voxel's centre and a 6-neighbour's (their
  // distances of opposite signs), nearer this one (a tie goes to the voxel in front).
  const float min_weight = static_cast<float>(options_.tsdf_min_weight);
  static constexpr int kNeighbours[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const auto& d : kNeighbours) {
    const std::uint64_t k = key({v.x + d[0], v.y + d[1], v.z + d[2]});
    const auto found = cells_.find(k);
    if (found == cells_.end()) continue;
    const auto [n, n_evidence] = judged(k, found->second);
    if (!(n_evidence >= min_weight) || (n.value >= 0.f) == (c.value >= 0.f)) continue;
    const float here = std::abs(c.value), there = std::abs(n.value);
    if (here < there || (here == there && c.value >= 0.f)) return VoxelState::kOccupied;
  }
  return std::abs(c.value) < 0.5 * options_.tsdf_truncation_m ? VoxelState::kNear : VoxelState::kUnknown;
}

std::unordered_map<std::uint64_t, VoxelMap::Fit> VoxelMap::fitted_distances(int min_layer, int max_layer) const {
  const int r = options_.tsdf_fit_radius;
  const float limit = 0.999f * static_cast<float>(options_.tsdf_truncation_m);
  // Voxels whose average is a distance to a surface: observed in a band, not at the truncation.
  const auto holds_distance = [&](const Cell& c) { return c.weight > 0.f && std::abs(c.value) < limit; };
  std::unordered_map<std::uint64_t, Fit> fitted;
  for (const auto& [k, c] : cells_) {
    if (!holds_distance(c)) continue;
    const VoxelIndex v = unkey(k);
    if (v.z < min_layer || v.z > max_layer) continue;
    // Weighted least squares of distance = a + g . offset over the neighbourhood; a is the fit at the centre.
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
    int count = 0;
    double pooled = 0.0;
    for (int dx = -r; dx <= r; ++dx) {
      for (int dy = -r; dy <= r; ++dy) {
        for (int dz = -r; dz <= r; ++dz) {
          const auto found = cells_.find(key({v.x + dx, v.y + dy, v.z + dz}));
          if (found == cells_.end() || !holds_distance(found->second)) continue;
          const Eigen::Vector4d row(1.0, dx, dy, dz);
          const double w = found->second.weight;
          normal.noalias() += w * row * row.transpose();
          rhs.noalias() += (w * found->second.value) * row;
          pooled += w;
          ++count;
        }
      }
    }
    if (count < 8) continue;
    const Eigen::LDLT<Eigen::Matrix4d> solver(normal);
    if (solver.info() != Eigen::Success || !(solver.rcond() > 1e-3)) continue;  // neighbours on a line or plane
    fitted.emplace(k, Fit{static_cast<float>(solver.solve(rhs)(0)), static_cast<float>(pooled)});
  }
  return fitted;
}

void VoxelMap::for_each_state(const std::function<void(const VoxelIndex&, VoxelState)>& visit, int min_layer,
                              int max_layer) const {
  std::unordered_map<std::uint64_t, Fit> fitted;
  const bool fit = options_.model == FusionModel::kTsdf && options_.tsdf_fit_radius > 0;
  if (fit) {
    // The layers' own fits and their neighbours' above and below (the zero crossing looks at them).
    fitted = fitted_distances(min_layer == std::numeric_limits<int>::min() ? min_layer : min_layer - 1,
                              max_layer == std::numeric_limits<int>::max() ? max_layer : max_layer + 1);
  }
  for (const auto& [k, c] : cells_) {
    const VoxelIndex v = unkey(k);
    if (v.z < min_layer || v.z > max_layer) continue;
    visit(v, state_at(v, c, fit ? &fitted : nullptr));
  }
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

std::size_t VoxelMap::integrate(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3f> points,
                                std::span<const float> sigmas_m, std::span<const Eigen::Vector3f> normals) {
  if (!origin.allFinite()) return 0;
  if (!sigmas_m.empty() && sigmas_m.size() != points.size()) {
    throw std::invalid_argument("voxel map: integrate got " + std::to_string(sigmas_m.size()) + " sigmas for " +
                                std::to_string(points.size()) + " points");
  }
  if (!normals.empty() && normals.size() != points.size()) {
    throw std::invalid_argument("voxel map: integrate got " + std::to_string(normals.size()) + " normals for " +
                                std::to_string(points.size()) + " points");
  }
  if (options_.model == FusionModel::kTsdf) return integrate_tsdf(origin, points, sigmas_m, normals);
  std::vector<std::uint64_t> hits;
  std::vector<std::uint64_t> misses;
  hits.reserve(points.size());
  std::size_t used = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d point = points[i].cast<double>();
    if (!point.allFinite() || (point - origin).norm() > options_.max_ray_m) continue;
    const double sigma = sigmas_m.empty() ? 0.0 : static_cast<double>(sigmas_m[i]);
    if (!std::isfinite(sigma)) continue;
    ++used;
    const std::uint64_t end_key = key(index_of(point));
    if (sigma <= options_.hit_max_sigma_m) hits.push_back(end_key);
    const double length = (point - origin).norm();
    const double margin = std::max(options_.free_margin_m, options_.free_sigmas * sigma);
    if (length <= margin) continue;
    const Eigen::Vector3d free_end = origin + (point - origin) * ((length - margin) / length);
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

std::size_t VoxelMap::integrate_tsdf(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3f> points,
                                     std::span<const float> sigmas_m, std::span<const Eigen::Vector3f> normals) {
  const double r = options_.resolution_m;
  const float truncation = static_cast<float>(options_.tsdf_truncation_m);
  // Per image: the voxels in some point's band (their weighted distances summed), and the voxels
  // crossed in front of every band (free). A voxel in a band takes only the band's distances (the
  // TSDF's "hit wins over miss": a ray passing a surface at a grazing angle does not carve it).
  struct Sample {
    std::uint64_t key;
    float sdf_times_weight;
    float weight;
  };
  std::vector<Sample> near;
  std::vector<std::uint64_t> crossed;
  std::size_t used = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d point = points[i].cast<double>();
    const double length = (point - origin).norm();
    if (!point.allFinite() || length > options_.max_ray_m || !(length > 0.0)) continue;
    const double sigma = sigmas_m.empty() ? 0.0 : static_cast<double>(sigmas_m[i]);
    if (!std::isfinite(sigma)) continue;
    ++used;
    const Eigen::Vector3d direction = (point - origin) / length;
    const double band = std::max(options_.tsdf_truncation_m, options_.free_sigmas * sigma);
    const float w = static_cast<float>(sigma > r ? (r / sigma) * (r / sigma) : 1.0);
    const bool hit = sigma <= options_.hit_max_sigma_m;
    const Eigen::Vector3d end = origin + direction * (length + (hit ? band : 0.0));
    const Eigen::Vector3d normal =
        normals.empty() ? Eigen::Vector3d(Eigen::Vector3d::Zero()) : Eigen::Vector3d(normals[i].cast<double>());
    const bool planar = normal.squaredNorm() > 0.5;
    walk(r, origin, end, [&](int x, int y, int z) {
      const Eigen::Vector3d centre((x + 0.5) * r, (y + 0.5) * r, (z + 0.5) * r);
      const double along = length - (centre - origin).dot(direction);  // > 0: in front of the point
      // The distance to the point's plane where its normal is known (towards the camera: > 0 in front).
      const double distance = planar ? (centre - point).dot(normal) : along;
      const std::uint64_t k = key({x, y, z});
      if (along > band && distance > band) {
        crossed.push_back(k);
      } else if (along > band) {
        return true;  // near the point's plane but far along the ray: a grazing ray; no evidence
      } else if (hit) {
        const float d = std::clamp(static_cast<float>(distance), -truncation, truncation);
        near.push_back({k, d * w, w});
      }
      return true;
    });
  }
  std::sort(near.begin(), near.end(), [](const Sample& a, const Sample& b) { return a.key < b.key; });
  std::sort(crossed.begin(), crossed.end());
  crossed.erase(std::unique(crossed.begin(), crossed.end()), crossed.end());
  // One observation per voxel and image: the band's weighted mean distance, with the mean weight.
  std::vector<std::uint64_t> banded;
  for (std::size_t begin = 0; begin < near.size();) {
    std::size_t end = begin;
    float sum = 0.f, weight = 0.f;
    for (; end < near.size() && near[end].key == near[begin].key; ++end) {
      sum += near[end].sdf_times_weight;
      weight += near[end].weight;
    }
    const float d = sum / weight;
    const float w = weight / static_cast<float>(end - begin);
    Cell& c = cells_[near[begin].key];
    c.value = (c.value * c.weight + d * w) / (c.weight + w);
    c.weight += w;
    banded.push_back(near[begin].key);
    begin = end;
  }
  auto in_band = banded.begin();
  for (const std::uint64_t k : crossed) {
    while (in_band != banded.end() && *in_band < k) ++in_band;
    if (in_band != banded.end() && *in_band == k) continue;
    cells_[k].crossed += 1.f;
  }
  return used;
}

void VoxelMap::for_each(const std::function<void(const VoxelIndex&, float)>& visit) const {
  for (const auto& [k, c] : cells_) visit(unkey(k), c.value);
}

std::size_t VoxelMap::memory_bytes() const {
  // A node: next pointer, key and cell padded as a pair (+ cached hash in libstdc++ only for non-fast
  // hashes); a bucket pointer.
  return cells_.size() * (sizeof(void*) + sizeof(std::pair<const std::uint64_t, Cell>)) +
         cells_.bucket_count() * sizeof(void*);
}

}  // namespace heslam
