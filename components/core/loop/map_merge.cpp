// Map merging: rigid move of the active map, seam fusion and essential graph, seam BA (map_merge.hpp).
#include "components/core/loop/map_merge.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "components/core/loop/live_map.hpp"
#include "components/core/map/ids.hpp"
#include "components/core/mapping/correction_application.hpp"
#include "components/core/mapping/covisibility.hpp"

namespace heslam {
namespace {

using loop_detail::Clock;
using loop_detail::live_keyframe;
using loop_detail::ms_since;

// Distance along the live keyframes of `keyframes` (id = creation order) between ids `from` and `to`.
double path_between(const Map& map, const std::set<KeyframeId>& keyframes, KeyframeId from, KeyframeId to) {
  double path_m = 0.0;
  const Keyframe* previous = nullptr;
  for (auto it = keyframes.lower_bound(std::min(from, to)); it != keyframes.end() && *it <= std::max(from, to); ++it) {
    const Keyframe* kf = map.keyframe(*it);
    if (kf == nullptr || kf->culled) continue;
    if (previous != nullptr) path_m += (kf->T_wc.translation() - previous->T_wc.translation()).norm();
    previous = kf;
  }
  return path_m;
}

// The keyframe of `keyframes` with the smallest (first) or largest (!first) stamp, ties by id.
const Keyframe* by_stamp(const Map& map, const std::set<KeyframeId>& keyframes, bool first) {
  const Keyframe* best = nullptr;
  for (const KeyframeId id : keyframes) {
    const Keyframe* kf = map.keyframe(id);
    if (kf == nullptr) continue;
    if (best == nullptr || (first ? kf->stamp_ns < best->stamp_ns : kf->stamp_ns > best->stamp_ns)) best = kf;
  }
  return best;
}

}  // namespace

std::string MapMerge::implausible_merge(const Map& map, const MapMergeRequest& request, const Pose3& T_BA,
                                        MapMergeStats* stats) const {
  char reason[320];
  if (options_.correction.pose_graph.four_dof) {
    const Eigen::Vector3d g = options_.correction.pose_graph.gravity_w.normalized();
    const double tilt_deg = std::acos(std::clamp((T_BA.rotation() * g).dot(g), -1.0, 1.0)) * 180.0 / M_PI;
    if (tilt_deg > options_.max_tilt_deg) {
      std::snprintf(reason, sizeof reason, "tilts one gravity-aligned map against the other by %.1f deg (allowed %.1f)",
                    tilt_deg, options_.max_tilt_deg);
      return reason;
    }
  }
  const Keyframe* a_first = by_stamp(map, request.active_map, /*first=*/true);
  const Keyframe* b_last = by_stamp(map, request.matched_map, /*first=*/false);
  if (options_.max_unobserved_speed_mps <= 0.0 || a_first == nullptr || b_last == nullptr ||
      a_first->stamp_ns <= b_last->stamp_ns) {
    return {};  // no temporal bound: the maps overlap in time, or the gate is off
  }
  const double gap_s = static_cast<double>(a_first->stamp_ns - b_last->stamp_ns) * 1e-9;
  const double unobserved_m = ((T_BA * a_first->T_wc.translation()) - b_last->T_wc.translation()).norm();
  const double path_m = path_between(map, request.active_map, a_first->id, request.active_kf) +
                        path_between(map, request.matched_map, request.matched_kf, b_last->id);
  const double allowed_m =
      options_.max_unobserved_speed_mps * gap_s + options_.max_drift_fraction * path_m + options_.min_drift_allowance_m;
  if (stats != nullptr) {
    stats->unobserved_m = unobserved_m;
    stats->allowed_m = allowed_m;
  }
  if (unobserved_m <= allowed_m) return {};
  std::snprintf(reason, sizeof reason,
                "implies %.2f m travelled unobserved in %.2f s between keyframe %s (last of the matched map) and "
                "keyframe %s (first of the active map) (allowed %.2f m: %.1f m/s and drift over %.1f m)",
                unobserved_m, gap_s, format_id(b_last->id).c_str(), format_id(a_first->id).c_str(), allowed_m,
                options_.max_unobserved_speed_mps, path_m);
  return reason;
}

MapMergeOutput MapMerge::compute(const Map& map, const PinholeStereo& camera, const MapMergeRequest& request,
                                 const std::vector<std::pair<KeyframeId, KeyframeId>>& previous_loop_edges) const {
  const auto start = Clock::now();
  MapMergeOutput output;
  if (!live_keyframe(map, request.active_kf) || !live_keyframe(map, request.matched_kf) ||
      request.active_map.count(request.active_kf) == 0 || request.matched_map.count(request.matched_kf) == 0) {
    output.error = "map merge: active keyframe " + format_id(request.active_kf) + " and matched keyframe " +
                   format_id(request.matched_kf) + " must be live keyframes of the active and the matched map";
    return output;
  }
  for (const KeyframeId id : request.active_map) {
    if (request.matched_map.count(id) != 0) {
      output.error = "map merge: keyframe " + format_id(id) + " is in both maps";
      return output;
    }
  }
  const Pose3 T_BA = map.keyframe(request.matched_kf)->T_wc * request.T_matched_active *
                     map.keyframe(request.active_kf)->T_wc.inverse();
  output.T_BA = T_BA;
  if (std::string why = implausible_merge(map, request, T_BA, &output.stats); !why.empty()) {
    output.error = "merge gate: " + why;
    output.gate_rejected = true;
    return output;
  }

  // The two maps alone, A moved into B's frame and into B's map id (a): one map from here on.
  const MapId into = map.keyframe(request.matched_kf)->map_id;
  Map joined;
  joined.version = map.version;
  std::set<PointId> points_a;
  for (const auto* side : {&request.active_map, &request.matched_map}) {
    const bool moved = side == &request.active_map;
    for (const KeyframeId id : *side) {
      const Keyframe* kf = map.keyframe(id);
      if (kf == nullptr) continue;
      Keyframe& copy = joined.keyframes.emplace(id, *kf).first->second;
      if (moved) {
        copy.T_wc = T_BA * copy.T_wc;
        copy.map_id = into;
      }
      for (const PointId point_id : kf->point_ids) {
        const MapPoint* point = point_id == kNoId ? nullptr : map.point(point_id);
        if (point == nullptr || joined.points.count(point_id) != 0) continue;
        MapPoint& point_copy = joined.points.emplace(point_id, *point).first->second;
        if (moved) {
          point_copy.map_id = into;
          point_copy.p_w = T_BA * point_copy.p_w;
          point_copy.normal = T_BA.rotation() * point_copy.normal;
          points_a.insert(point_id);
        }
      }
    }
  }
  for (const auto& [id, kf] : joined.keyframes) {
    if (!kf.culled && request.active_map.count(id) != 0) ++output.stats.moved_keyframes;
  }
  output.stats.moved_points = static_cast<int>(points_a.size());

  // (b) Seam fusion, joined covisibility and the essential graph of the union. On the moved copy the
  // verified relative pose is the identity correction for A's seam group.
  LoopCandidate seam;
  seam.loop_kf = request.active_kf;
  seam.matched_kf = request.matched_kf;
  seam.T_matched_loop = request.T_matched_active;
  seam.matched_points = request.matched_points;
  std::vector<std::pair<KeyframeId, KeyframeId>> edges;
  for (const auto& edge : previous_loop_edges) {
    if (joined.keyframes.count(edge.first) != 0 && joined.keyframes.count(edge.second) != 0) edges.push_back(edge);
  }
  LoopCorrectionOutput welded = LoopCorrectionBuilder(options_.correction).compute(joined, camera, seam, edges);
  if (!welded.error.empty()) {
    output.error = "map merge: " + welded.error;
    return output;
  }
  MapChanges changes;
  apply_loop_correction(joined, welded.correction, {}, changes);
  std::set<KeyframeId> affected;
  for (const auto& [from, into] : welded.correction.point_merges) {
    for (const auto& [kf_id, index] : joined.points.at(into).observations) affected.insert(kf_id);
  }
  for (const KeyframeId id : affected) update_connections(joined, id, CovisibilityOptions{});
  std::set<std::pair<KeyframeId, KeyframeId>> seam_pairs;
  for (const auto& [id, kf] : joined.keyframes) {
    if (kf.culled || request.active_map.count(id) == 0) continue;
    for (const auto& [neighbour, weight] : kf.covisible) {
      if (request.matched_map.count(neighbour) != 0) seam_pairs.emplace(id, neighbour);
    }
  }
  output.stats.seam_connections = static_cast<int>(seam_pairs.size());

  // (c) The seam BA: the active keyframe's covisible group now spans both maps.
  if (options_.seam_bundle_adjustment) {
    MapChanges ba_changes;
    output.stats.seam_ba = local_bundle_adjustment(joined, request.active_kf, camera, options_.seam_ba, ba_changes);
  }

  // (d) Every live keyframe and point of the union where the copy left it.
  LoopCorrection& correction = output.correction;
  correction.kind = CorrectionKind::kMerge;
  correction.map_version = map.version;
  correction.loop_kf = request.active_kf;
  correction.matched_kf = request.matched_kf;
  correction.T_matched_loop = request.T_matched_active;
  for (const auto& [id, kf] : joined.keyframes) {
    if (!kf.culled) correction.corrected_T_wc.emplace_back(id, kf.T_wc);
  }
  correction.point_merges = welded.correction.point_merges;
  for (const auto& [id, point] : joined.points) {
    if (!point.culled && point.merged_into == kNoId) correction.corrected_points.emplace_back(id, point.p_w);
  }
  output.stats.point_merges = static_cast<int>(correction.point_merges.size());
  output.stats.total_ms = ms_since(start);
  return output;
}

}  // namespace heslam
