// CorrectLoop as a pure function: group correction, duplicate search, loop connections, essential graph.
#include "components/core/loop/loop_correction_builder.hpp"

#include <chrono>
#include <set>

#include "components/core/loop/keyframe_projection.hpp"
#include "components/core/loop/live_map.hpp"
#include "components/core/map/ids.hpp"
#include "components/core/mapping/point_statistics.hpp"
#include "components/core/match/feature_grid.hpp"

namespace heslam {
namespace {

using loop_detail::Clock;
using loop_detail::live_keyframe;
using loop_detail::live_point;
using loop_detail::ms_since;

// The keyframe first, then its live covisible keyframes by weight (ORB-SLAM2's connected keyframes).
std::vector<KeyframeId> group_of(const Map& map, KeyframeId id) {
  std::vector<KeyframeId> group{id};
  for (const auto& [neighbour, weight] : map.keyframe(id)->covisible) {
    if (neighbour != id && live_keyframe(map, neighbour)) group.push_back(neighbour);
  }
  return group;
}

// Live points observed by the group, each once, in group order.
std::vector<PointId> points_of(const Map& map, const std::vector<KeyframeId>& group) {
  std::vector<PointId> points;
  std::set<PointId> seen;
  for (const KeyframeId kf_id : group) {
    for (const PointId id : map.keyframe(kf_id)->point_ids) {
      if (id != kNoId && live_point(map, id) && seen.insert(id).second) points.push_back(id);
    }
  }
  return points;
}

// Each loop-side point is merged at most once, and never into a point that is itself merged away.
class MergeList {
 public:
  bool add(PointId from, PointId into) {
    if (from == into || into_of_.count(from) != 0 || into_of_.count(into) != 0) return false;
    into_of_[from] = into;
    sources_[into].push_back(from);
    merges_.emplace_back(from, into);
    return true;
  }
  PointId resolve(PointId id) const {
    const auto it = into_of_.find(id);
    return it == into_of_.end() ? id : it->second;
  }
  bool merged(PointId id) const { return into_of_.count(id) != 0; }
  const std::vector<PointId>& sources(PointId into) const {
    static const std::vector<PointId> none;
    const auto it = sources_.find(into);
    return it == sources_.end() ? none : it->second;
  }
  const std::vector<std::pair<PointId, PointId>>& merges() const { return merges_; }

 private:
  std::map<PointId, PointId> into_of_;
  std::map<PointId, std::vector<PointId>> sources_;
  std::vector<std::pair<PointId, PointId>> merges_;
};

// (c) Projects the matched side's points into every corrected loop-group keyframe; a keypoint holding
// a loop-side point makes a merge. Returns the matches on free keypoints (not representable).
int search_duplicates(const Map& map, const PinholeStereo& camera, const std::map<KeyframeId, Pose3>& corrected_T_wc,
                      const std::vector<KeyframeId>& loop_group, const std::set<PointId>& loop_points,
                      const std::vector<PointId>& matched_points, const LoopCorrectionBuilderOptions& options,
                      MergeList& merges) {
  int unlinked = 0;
  ProjectionMatchOptions projection;
  projection.radius_px = options.fuse_radius_px;
  projection.max_descriptor_distance = options.max_descriptor_distance;
  projection.min_view_cos = options.min_view_cos;
  for (const KeyframeId kf_id : loop_group) {
    const Keyframe& kf = *map.keyframe(kf_id);
    const FeatureGrid grid(kf.features.keypoints, camera.width_px, camera.height_px);
    for (const PointId matched_id : matched_points) {
      const int index =
          best_projection_match(*map.point(matched_id), kf, corrected_T_wc.at(kf_id), grid, camera, projection);
      if (index < 0) continue;
      const PointId existing = kf.point_ids[static_cast<std::size_t>(index)];
      if (existing == kNoId || !live_point(map, existing)) {
        ++unlinked;
        continue;
      }
      if (loop_points.count(existing) != 0) merges.add(existing, matched_id);
    }
  }
  return unlinked;
}

// (d) Covisibility of the loop group with keyframes outside it that only the merges created
// (ORB-SLAM2: connections after the fusion minus the neighbours before it). The loop keyframe -
// matched keyframe link comes first and is always kept.
std::vector<LoopConnection> loop_connections(const Map& map, const LoopCandidate& loop,
                                             const std::vector<KeyframeId>& loop_group, const MergeList& merges) {
  const std::set<KeyframeId> in_group(loop_group.begin(), loop_group.end());
  std::vector<LoopConnection> connections{{loop.loop_kf, loop.matched_kf, 0, true}};
  for (const KeyframeId kf_id : loop_group) {
    const Keyframe& kf = *map.keyframe(kf_id);
    std::set<KeyframeId> previous{kf_id};
    for (const auto& [neighbour, weight] : kf.covisible) previous.insert(neighbour);
    std::map<KeyframeId, int> shared;
    std::set<PointId> counted;
    for (const PointId point_id : kf.point_ids) {
      if (point_id == kNoId || !live_point(map, point_id) || !merges.merged(point_id)) continue;
      const PointId into = merges.resolve(point_id);
      if (!counted.insert(into).second) continue;
      std::set<KeyframeId> observers;
      for (const auto& [observer, index] : map.point(into)->observations) observers.insert(observer);
      for (const PointId source : merges.sources(into)) {
        for (const auto& [observer, index] : map.point(source)->observations) observers.insert(observer);
      }
      for (const KeyframeId observer : observers) {
        if (in_group.count(observer) == 0 && previous.count(observer) == 0) ++shared[observer];
      }
    }
    for (const auto& [neighbour, count] : shared) {
      if (kf_id == loop.loop_kf && neighbour == loop.matched_kf) {
        connections.front().shared_points = count;
      } else {
        connections.push_back({kf_id, neighbour, count, false});
      }
    }
  }
  return connections;
}

}  // namespace

LoopCorrectionOutput LoopCorrectionBuilder::compute(
    const Map& map, const PinholeStereo& camera, const LoopCandidate& loop,
    const std::vector<std::pair<KeyframeId, KeyframeId>>& previous_loop_edges) const {
  const auto start = Clock::now();
  LoopCorrectionOutput output;
  if (!live_keyframe(map, loop.loop_kf) || !live_keyframe(map, loop.matched_kf) || loop.loop_kf == loop.matched_kf) {
    output.error = "loop correction: loop keyframe " + format_id(loop.loop_kf) + " and matched keyframe " +
                   format_id(loop.matched_kf) + " must be two distinct live keyframes of the map";
    return output;
  }
  LoopCorrection& correction = output.correction;
  correction.map_version = map.version;
  correction.loop_kf = loop.loop_kf;
  correction.matched_kf = loop.matched_kf;
  correction.T_matched_loop = loop.T_matched_loop;

  // (a) The loop group moves rigidly with the loop keyframe's corrected pose.
  const std::vector<KeyframeId> loop_group = group_of(map, loop.loop_kf);
  const Pose3& T_w_loop = map.keyframe(loop.loop_kf)->T_wc;
  Pose3 correction_w = map.keyframe(loop.matched_kf)->T_wc * loop.T_matched_loop * T_w_loop.inverse();
  if (options_.pose_graph.four_dof) {
    // Inertial: the loop keyframe goes to the verified position, turned only about gravity (ORB-SLAM3
    // zeroes the correction's roll and pitch), so the group's roll and pitch stay the IMU's.
    const Eigen::Vector3d target = correction_w * T_w_loop.translation();
    correction_w.linear() = yaw_about_gravity(correction_w.rotation(), options_.pose_graph.gravity_w);
    correction_w.translation() = target - correction_w.rotation() * T_w_loop.translation();
  }
  std::map<KeyframeId, Pose3> corrected_T_wc;
  for (const KeyframeId id : loop_group) corrected_T_wc[id] = correction_w * map.keyframe(id)->T_wc;

  // (b) So do its points.
  const std::vector<PointId> loop_points = points_of(map, loop_group);
  const std::set<PointId> loop_point_set(loop_points.begin(), loop_points.end());
  for (const PointId id : loop_points) output.loop_group_p_w[id] = correction_w * map.point(id)->p_w;

  // (c) Duplicates: known matches first, then the matched group's points projected into the loop group.
  const auto fusion_start = Clock::now();
  MergeList merges;
  for (const auto& [loop_side, matched_side] : loop.matched_points) {
    if (loop_point_set.count(loop_side) != 0 && loop_point_set.count(matched_side) == 0 &&
        live_point(map, matched_side)) {
      merges.add(loop_side, matched_side);
    }
  }
  const std::vector<KeyframeId> matched_group = group_of(map, loop.matched_kf);
  std::vector<PointId> matched_points;
  for (const PointId id : points_of(map, matched_group)) {
    if (loop_point_set.count(id) == 0) matched_points.push_back(id);
  }
  output.stats.unlinked_matches =
      search_duplicates(map, camera, corrected_T_wc, loop_group, loop_point_set, matched_points, options_, merges);
  correction.point_merges = merges.merges();
  output.stats.fusion_ms = ms_since(fusion_start);

  // (d) Loop connections and the essential graph, the matched keyframe fixed.
  const std::vector<LoopConnection> connections = loop_connections(map, loop, loop_group, merges);
  for (const LoopConnection& connection : connections) {
    if (connection.always || connection.shared_points >= options_.essential_graph.min_covisibility_weight) {
      ++output.stats.loop_connections;
    }
  }

  EssentialGraph graph =
      EssentialGraphBuilder(options_.essential_graph).compute(map, corrected_T_wc, connections, previous_loop_edges);
  std::map<KeyframeId, Pose3> initial_T_wc;
  for (const auto& [id, kf] : map.keyframes) {
    if (kf.culled) continue;
    const auto it = corrected_T_wc.find(id);
    initial_T_wc[id] = it != corrected_T_wc.end() ? it->second : kf.T_wc;
  }
  std::set<KeyframeId> fixed{loop.matched_kf};
  if (options_.fix_loop_group) fixed.insert(loop_group.begin(), loop_group.end());
  const PoseGraphResult optimized = PoseGraph(options_.pose_graph).compute(initial_T_wc, graph.edges, fixed);

  // (e) Every live keyframe's new pose.
  for (const auto& [id, T_wc] : optimized.T_wc) correction.corrected_T_wc.emplace_back(id, T_wc);

  LoopCorrectionStats& stats = output.stats;
  stats.loop_group_keyframes = static_cast<int>(loop_group.size());
  stats.matched_group_keyframes = static_cast<int>(matched_group.size());
  stats.loop_group_points = static_cast<int>(loop_points.size());
  stats.matched_group_points = static_cast<int>(matched_points.size());
  stats.point_merges = static_cast<int>(correction.point_merges.size());
  graph.edges.clear();
  stats.graph_edges = graph;
  stats.pose_graph = optimized.stats;
  stats.total_ms = ms_since(start);
  return output;
}

}  // namespace heslam
