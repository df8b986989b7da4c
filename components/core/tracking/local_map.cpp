// Local map selection and keyframe creation / insertion for the tracker.
#include "components/core/tracking/local_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "components/core/camera/pinhole_stereo.hpp"

namespace heslam {
namespace {

// Covisibility edges need this many shared points (ORB-SLAM2 UpdateConnections); a keyframe with no
// such neighbour keeps an edge to its best one so the graph stays connected.
constexpr int kMinCovisibilityWeight = 15;

// Most-shared first; ties by id so the order never depends on container history.
void sort_by_weight(std::vector<std::pair<KeyframeId, int>>& edges) {
  std::sort(edges.begin(), edges.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
}

void set_edge(Keyframe& keyframe, KeyframeId other, int weight) {
  for (auto& edge : keyframe.covisible) {
    if (edge.first == other) {
      edge.second = weight;
      sort_by_weight(keyframe.covisible);
      return;
    }
  }
  keyframe.covisible.emplace_back(other, weight);
  sort_by_weight(keyframe.covisible);
}

// Without a local mapper nothing refines a point after its creation; each new stereo observation
// is an independent measurement of it, so the position becomes their inverse-variance weighted mean
// (stereo depth variance grows with depth^4 at fixed disparity noise).
void fuse_stereo_positions(MapPoint& point, const Map& map, const PinholeStereo& camera) {
  Eigen::Vector3d weighted_sum = Eigen::Vector3d::Zero();
  double weight_sum = 0.0;
  for (const auto& [kf_id, index] : point.observations) {
    const Keyframe* kf = map.keyframe(kf_id);
    if (kf == nullptr) continue;
    const std::size_t i = static_cast<std::size_t>(index);
    if (!kf->features.has_stereo(i)) continue;
    const Keypoint& kp = kf->features.keypoints[i];
    const double depth_m = kf->features.depth_m[i];
    const double weight = kf->features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)] / std::pow(depth_m, 4);
    weighted_sum += weight * (kf->T_wc * camera.unproject(kp.u_px, kp.v_px, depth_m));
    weight_sum += weight;
  }
  if (weight_sum > 0.0) point.p_w = weighted_sum / weight_sum;
}

// Mean viewing direction over all observing keyframes, and the representative descriptor: the one with
// the least median distance to the others (ORB-SLAM2 ComputeDistinctiveDescriptors).
void refresh_point(MapPoint& point, const Map& map, const PinholeStereo* camera) {
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
  std::vector<const Descriptor*> descriptors;
  for (const auto& [kf_id, index] : point.observations) {
    const Keyframe* kf = map.keyframe(kf_id);
    if (kf == nullptr) continue;
    normal_sum += (point.p_w - kf->T_wc.translation()).normalized();
    descriptors.push_back(&kf->features.descriptors[static_cast<std::size_t>(index)]);
  }
  if (normal_sum.norm() > 0.0) point.normal = normal_sum.normalized();
  if (camera != nullptr) fuse_stereo_positions(point, map, *camera);
  if (descriptors.size() < 3) return;  // with two, either is as representative as the other
  const std::size_t n = descriptors.size();
  int best_median = std::numeric_limits<int>::max();
  std::size_t best = 0;
  std::vector<int> row(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) row[j] = i == j ? 0 : hamming_distance(*descriptors[i], *descriptors[j]);
    std::nth_element(row.begin(), row.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  point.descriptor = *descriptors[best];
}

}  // namespace

void init_point_geometry(MapPoint& point, const Keyframe& keyframe, int keypoint_index) {
  const Eigen::Vector3d ray = point.p_w - keyframe.T_wc.translation();
  const double distance = ray.norm();
  point.normal = distance > 0.0 ? Eigen::Vector3d(ray / distance) : Eigen::Vector3d::UnitZ();
  const ScalePyramid& pyramid = keyframe.features.pyramid;
  const int octave = keyframe.features.keypoints[static_cast<std::size_t>(keypoint_index)].octave;
  point.max_distance_m = static_cast<float>(distance) * pyramid.scale[static_cast<std::size_t>(octave)];
  point.min_distance_m = point.max_distance_m / pyramid.scale[static_cast<std::size_t>(pyramid.levels - 1)];
  point.reference_kf = keyframe.id;
}

LocalMapSelection select_local_map(const Frame& frame, const Map& map, const TrackerOptions& options) {
  LocalMapSelection selection;
  // Votes: keyframes observing the frame's matched points, one entry per observation, sorted so that
  // equal ids form runs (ascending id, as a std::map of counts would give, without a node per id).
  std::vector<KeyframeId> voters;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] == kNoId || frame.outlier[i]) continue;
    const MapPoint* point = map.point(frame.point_ids[i]);
    if (point == nullptr || point->culled) continue;
    for (const auto& observation : point->observations) voters.push_back(observation.first);
  }
  std::sort(voters.begin(), voters.end());
  int best_votes = 0;
  for (std::size_t run = 0; run < voters.size();) {
    const KeyframeId id = voters[run];
    std::size_t end = run + 1;
    while (end < voters.size() && voters[end] == id) ++end;
    const int count = static_cast<int>(end - run);
    run = end;
    const Keyframe* kf = map.keyframe(id);
    if (kf == nullptr || kf->culled) continue;
    selection.keyframes.push_back(id);
    if (count > best_votes) {
      best_votes = count;
      selection.reference = id;
    }
  }
  // At most local_map_max_keyframes (80) ids: a linear search is cheaper than a node-based set.
  const auto chosen = [&](KeyframeId id) {
    return std::find(selection.keyframes.begin(), selection.keyframes.end(), id) != selection.keyframes.end();
  };
  // Neighbours of the voted keyframes: best covisible ones and the spanning-tree parent.
  const std::size_t voted = selection.keyframes.size();
  const std::size_t cap = static_cast<std::size_t>(std::max(options.local_map_max_keyframes, 1));
  for (std::size_t k = 0; k < voted && selection.keyframes.size() < cap; ++k) {
    const Keyframe* kf = map.keyframe(selection.keyframes[k]);
    int added = 0;
    for (const auto& [neighbour, weight] : kf->covisible) {
      if (added >= options.local_map_neighbours_per_keyframe || selection.keyframes.size() >= cap) break;
      const Keyframe* other = map.keyframe(neighbour);
      if (other == nullptr || other->culled || chosen(neighbour)) continue;
      selection.keyframes.push_back(neighbour);
      ++added;
    }
    const Keyframe* parent = map.keyframe(kf->parent);
    if (parent != nullptr && !parent->culled && !chosen(kf->parent) && selection.keyframes.size() < cap) {
      selection.keyframes.push_back(kf->parent);
    }
  }
  // Gather, sort, dedupe: far cheaper than a node-based set for thousands of ids.
  std::vector<PointId>& points = selection.points;
  for (KeyframeId id : selection.keyframes) {
    for (PointId pid : map.keyframe(id)->point_ids) {
      if (pid != kNoId) points.push_back(pid);
    }
  }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  // Culled or missing points stay: their only user, search_local_points, looks every point up and
  // skips those itself; filtering here was a second map lookup per point (3 % of the tracking).
  return selection;
}

KeyframeCandidate make_keyframe(const Frame& frame, const PinholeStereo& camera, const Map& map, KeyframeId keyframe_id,
                                std::uint64_t& next_point_counter, const TrackerOptions& options, MapId map_id) {
  KeyframeCandidate candidate;
  Keyframe& kf = candidate.keyframe;
  kf.id = keyframe_id;
  kf.map_id = map_id;
  kf.stamp_ns = frame.stamp_ns;
  kf.T_wc = frame.T_wc;
  kf.features = frame.features;
  kf.point_ids.assign(frame.size(), kNoId);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] != kNoId && !frame.outlier[i] && map.point(frame.point_ids[i]) != nullptr) {
      kf.point_ids[i] = frame.point_ids[i];
    }
  }

  // Stereo features nearest first; every close one becomes a point, far ones until enough points.
  std::vector<std::pair<float, std::size_t>> by_depth;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.features.has_stereo(i)) by_depth.emplace_back(frame.features.depth_m[i], i);
  }
  std::sort(by_depth.begin(), by_depth.end());
  const double close_depth_m = options.close_depth_baselines * camera.baseline_m;
  int points = 0;
  for (const auto& [depth_m, i] : by_depth) {
    if (kf.point_ids[i] == kNoId) {
      const Keypoint& kp = frame.features.keypoints[i];
      MapPoint point;
      point.id = make_id(options.id_tag, next_point_counter++);
      point.map_id = kf.map_id;
      point.p_w = frame.T_wc * camera.unproject(kp.u_px, kp.v_px, depth_m);
      point.descriptor = frame.features.descriptors[i];
      point.observations.emplace_back(kf.id, static_cast<int>(i));
      init_point_geometry(point, kf, static_cast<int>(i));
      kf.point_ids[i] = point.id;
      candidate.new_points.push_back(std::move(point));
    }
    ++points;
    if (depth_m > close_depth_m && points > options.new_keyframe_min_points) break;
  }
  return candidate;
}

void insert_keyframe(Map& map, const KeyframeCandidate& candidate, const PinholeStereo& camera,
                     const TrackerOptions& options) {
  const Keyframe& source = candidate.keyframe;
  Keyframe& kf = map.keyframes[source.id] = source;
  for (const MapPoint& point : candidate.new_points) map.points[point.id] = point;
  ++map.version;
  if (!options.maintain_map) return;

  std::map<KeyframeId, int> shared;
  for (std::size_t i = 0; i < kf.point_ids.size(); ++i) {
    MapPoint* point = map.point(kf.point_ids[i]);
    if (point == nullptr) continue;
    const bool observed = std::any_of(point->observations.begin(), point->observations.end(),
                                      [&](const auto& o) { return o.first == kf.id; });
    if (!observed) {
      for (const auto& observation : point->observations) ++shared[observation.first];
      point->observations.emplace_back(kf.id, static_cast<int>(i));
      refresh_point(*point, map, options.fuse_stereo_observations ? &camera : nullptr);
    }
  }
  KeyframeId best = kNoId;
  int best_weight = 0;
  for (const auto& [other_id, weight] : shared) {
    Keyframe* other = map.keyframe(other_id);
    if (other == nullptr || other_id == kf.id) continue;
    if (weight > best_weight) {
      best_weight = weight;
      best = other_id;
    }
    if (weight >= kMinCovisibilityWeight) {
      set_edge(kf, other_id, weight);
      set_edge(*other, kf.id, weight);
    }
  }
  if (best != kNoId) {
    if (kf.covisible.empty()) {
      set_edge(kf, best, best_weight);
      set_edge(*map.keyframe(best), kf.id, best_weight);
    }
    kf.parent = best;
  }
}

}  // namespace heslam
