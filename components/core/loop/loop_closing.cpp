// The loop closer's core: detection, geometric verification, correction, global BA.
#include "components/core/loop/loop_closing.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "components/core/loop/global_bundle_adjustment.hpp"
#include "components/core/loop/keyframe_projection.hpp"
#include "components/core/loop/loop_correction_builder.hpp"
#include "components/core/loop/se3_ransac.hpp"
#include "components/core/map/ids.hpp"
#include "components/core/match/feature_grid.hpp"

namespace heslam {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

const MapPoint* live_point(const Map& map, PointId id) {
  const MapPoint* point = id == kNoId ? nullptr : map.point(id);
  return point != nullptr && !point->culled ? point : nullptr;
}

// Distance travelled from keyframe `from` to keyframe `to` along the live keyframes between them (ids
// grow in creation order), on the map's current poses.
double path_between(const Map& map, KeyframeId from, KeyframeId to) {
  double path_m = 0.0;
  const Keyframe* previous = nullptr;
  for (auto it = map.keyframes.lower_bound(std::min(from, to));
       it != map.keyframes.end() && it->first <= std::max(from, to); ++it) {
    if (it->second.culled) continue;
    if (previous != nullptr) path_m += (it->second.T_wc.translation() - previous->T_wc.translation()).norm();
    previous = &it->second;
  }
  return path_m;
}

// Empty when the loop's implied drift is plausible, else why not (LoopClosingOptions, drift gate).
std::string implausible_drift(const Map& map, const Keyframe& loop_kf, const Keyframe& matched,
                              const Pose3& T_matched_loop, const LoopClosingOptions& options) {
  const Pose3 T_wc_loop_corrected = matched.T_wc * T_matched_loop;
  const Pose3 delta = loop_kf.T_wc.inverse() * T_wc_loop_corrected;
  const double drift_m = (T_wc_loop_corrected.translation() - loop_kf.T_wc.translation()).norm();
  const double drift_deg = Eigen::AngleAxisd(delta.linear()).angle() * 180.0 / M_PI;
  const double path_m = path_between(map, matched.id, loop_kf.id);
  const double allowed_m = options.max_drift_fraction * path_m + options.min_drift_allowance_m;
  const double allowed_deg = options.max_rotation_drift_deg_per_m * path_m + options.min_rotation_allowance_deg;
  if (drift_m <= allowed_m && drift_deg <= allowed_deg) return {};
  char reason[160];
  std::snprintf(reason, sizeof reason,
                "implies %.2f m / %.1f deg of drift over %.1f m travelled (allowed %.2f m / %.1f deg)", drift_m,
                drift_deg, path_m, allowed_m, allowed_deg);
  return reason;
}

// How many of the live points of the keyframes `group` match a keypoint of `kf` when `kf` is placed at
// T_wc (each point and each keypoint once): the verification's top-up, for another keyframe. `in_view`
// (optional) receives how many of them pass the projection test there (predict_view).
int projection_matches(const Map& map, const Keyframe& kf, const Pose3& T_wc, const std::vector<KeyframeId>& group,
                       const PinholeStereo& camera, const ProjectionMatchOptions& projection, int* in_view = nullptr) {
  const FeatureGrid grid(kf.features.keypoints, camera.width_px, camera.height_px);
  std::vector<bool> taken(kf.features.size(), false);
  std::set<PointId> seen;
  int matches = 0;
  if (in_view != nullptr) *in_view = 0;
  for (const KeyframeId kf_id : group) {
    const Keyframe* member = map.keyframe(kf_id);
    if (member == nullptr || member->culled) continue;
    for (const PointId point_id : member->point_ids) {
      const MapPoint* point = live_point(map, point_id);
      if (point == nullptr || !seen.insert(point_id).second) continue;
      if (in_view != nullptr && predict_view(*point, T_wc, camera, projection)) ++*in_view;
      const int index = best_projection_match(*point, kf, T_wc, grid, camera, projection);
      if (index < 0 || taken[static_cast<std::size_t>(index)]) continue;
      taken[static_cast<std::size_t>(index)] = true;
      ++matches;
    }
  }
  return matches;
}

// `kf` and its covisible keyframes.
std::vector<KeyframeId> covisible_group(const Keyframe& kf) {
  std::vector<KeyframeId> group{kf.id};
  for (const auto& [neighbour, weight] : kf.covisible) group.push_back(neighbour);
  return group;
}

// Whether map `a` (first keyframe stamp `a_first_ns`) is older than map `b`. One agent numbers its maps
// in creation order (a new map takes the next id after every map of the agent it knows, a loaded saved
// map's included), so the smaller id is the older, whatever the stamps of the data (a session may replay
// an earlier recording than the saved map's). Two agents' maps are made at once by different frontends:
// the one whose first keyframe is older (equal stamps: the smaller id).
bool older_map(MapId a, std::int64_t a_first_ns, MapId b, std::int64_t b_first_ns) {
  if (agent_of_map(a) == agent_of_map(b) || a_first_ns == b_first_ns) return a < b;
  return a_first_ns < b_first_ns;
}

}  // namespace

LoopClosing::LoopClosing(const PinholeStereo& camera, std::unique_ptr<LoopDetector> detector,
                         const LoopClosingOptions& options)
    : camera_(camera), detector_(std::move(detector)), options_(options) {
  options_.merge.correction = options_.correction;  // fusion, essential graph and pose graph as the loops'
}

LoopClosing::~LoopClosing() = default;

std::optional<VerifiedPlace> LoopClosing::verify_place(const Map& map, KeyframeId query, KeyframeId candidate_id,
                                                       bool drift_gate, std::string& why) const {
  const Keyframe* query_kf = map.keyframe(query);
  const Keyframe* candidate = map.keyframe(candidate_id);
  if (query_kf == nullptr || query_kf->culled || candidate == nullptr || candidate->culled) {
    why = "culled before verification";
    return std::nullopt;
  }
  const Keyframe& loop_kf = *query_kf;
  // 3D-3D correspondences from the detector's matches: A = the candidate, B = the loop keyframe, so
  // the RANSAC transform T_ab is T_matched_loop.
  const auto pairs = detector_->match(map, query, candidate_id);
  std::vector<Se3Correspondence> correspondences;
  std::vector<std::pair<PointId, PointId>> correspondence_points;
  const Pose3 T_loop_w = loop_kf.T_wc.inverse();
  const Pose3 T_candidate_w = candidate->T_wc.inverse();
  for (const auto& [i, j] : pairs) {
    const MapPoint* loop_point = live_point(map, loop_kf.point_ids[i]);
    const MapPoint* matched_point = live_point(map, candidate->point_ids[j]);
    if (loop_point == nullptr || matched_point == nullptr) continue;
    const Keypoint& kp_loop = loop_kf.features.keypoints[i];
    const Keypoint& kp_matched = candidate->features.keypoints[j];
    Se3Correspondence c;
    c.p_a = T_candidate_w * matched_point->p_w;
    c.p_b = T_loop_w * loop_point->p_w;
    c.uv_a_px = {kp_matched.u_px, kp_matched.v_px};
    c.uv_b_px = {kp_loop.u_px, kp_loop.v_px};
    c.sigma2_a = candidate->features.pyramid.sigma2[static_cast<std::size_t>(kp_matched.octave)];
    c.sigma2_b = loop_kf.features.pyramid.sigma2[static_cast<std::size_t>(kp_loop.octave)];
    correspondences.push_back(c);
    correspondence_points.emplace_back(loop_point->id, matched_point->id);
  }
  if (static_cast<int>(correspondences.size()) < options_.min_candidate_matches) {
    why =
        std::to_string(correspondences.size()) + " matches (< " + std::to_string(options_.min_candidate_matches) + ")";
    return std::nullopt;
  }
  Se3RansacOptions ransac_options;
  ransac_options.min_inliers = options_.min_ransac_inliers;
  ransac_options.seed = options_.ransac_seed ^ query ^ (candidate_id << 1);
  const auto ransac = Se3Ransac(ransac_options).compute(camera_, correspondences);
  if (!ransac) {
    why = "SE(3) RANSAC: fewer than " + std::to_string(options_.min_ransac_inliers) + " of " +
          std::to_string(correspondences.size()) + " matches agree";
    return std::nullopt;
  }
  if (drift_gate) {
    if (std::string reason = implausible_drift(map, loop_kf, *candidate, ransac->T_ab, options_); !reason.empty()) {
      why = "drift gate: " + reason;
      return std::nullopt;
    }
  }
  VerifiedPlace verified;
  verified.T_matched_loop = ransac->T_ab;
  std::set<PointId> matched_side;
  for (std::size_t k = 0; k < correspondences.size(); ++k) {
    if (!ransac->inlier[k]) continue;
    verified.matched_points.push_back(correspondence_points[k]);
    matched_side.insert(correspondence_points[k].second);
  }
  // Top-up (ORB-SLAM2 SearchByProjection in ComputeSim3): the candidate's covisible group's points,
  // projected into the loop keyframe placed where the loop says it is.
  verified.matches = ransac->inliers;
  {
    const Pose3 T_wc_corrected = candidate->T_wc * ransac->T_ab;
    const FeatureGrid grid(loop_kf.features.keypoints, camera_.width_px, camera_.height_px);
    std::vector<bool> taken(loop_kf.features.size(), false);
    for (const auto& [loop_point, matched_point] : verified.matched_points) {
      for (std::size_t i = 0; i < loop_kf.point_ids.size(); ++i) {
        if (loop_kf.point_ids[i] == loop_point) taken[i] = true;
      }
    }
    std::vector<KeyframeId> group{candidate_id};
    for (const auto& [neighbour, weight] : candidate->covisible) group.push_back(neighbour);
    std::set<PointId> seen = matched_side;
    ProjectionMatchOptions projection;
    projection.radius_px = options_.projection_radius_px;
    projection.max_descriptor_distance = options_.matching.descriptor_threshold_low;
    for (const KeyframeId kf_id : group) {
      const Keyframe* kf = map.keyframe(kf_id);
      if (kf == nullptr || kf->culled) continue;
      for (const PointId point_id : kf->point_ids) {
        const MapPoint* point = live_point(map, point_id);
        if (point == nullptr || !seen.insert(point_id).second) continue;
        const int index = best_projection_match(*point, loop_kf, T_wc_corrected, grid, camera_, projection);
        if (index < 0 || taken[static_cast<std::size_t>(index)]) continue;
        taken[static_cast<std::size_t>(index)] = true;
        ++verified.matches;
      }
    }
  }
  if (verified.matches < options_.min_loop_matches) {
    why = std::to_string(verified.matches) + " matches after the projection top-up (< " +
          std::to_string(options_.min_loop_matches) + ")";
    return std::nullopt;
  }
  return verified;
}

LoopClosingResult LoopClosing::process_keyframe(const Map& map, KeyframeId query) {
  LoopClosingResult result;
  const auto detection_start = Clock::now();
  result.candidates = detector_->detect(map, query);
  result.timings.detection_ms = ms_since(detection_start);
  if (result.candidates.keyframes.empty()) return result;

  const auto verification_start = Clock::now();
  std::optional<VerifiedPlace> accepted;
  KeyframeId accepted_kf = kNoId;
  const MapId query_map = map.keyframe(query)->map_id;
  for (const KeyframeId candidate_id : result.candidates.keyframes) {
    // The atlas: a place of another map is no loop (its poses are in another world frame); recognising
    // it is a merge of the two maps (process_merge).
    if (const Keyframe* candidate = map.keyframe(candidate_id);
        candidate != nullptr && candidate->map_id != query_map) {
      result.rejected.push_back({candidate_id, "in map " + std::to_string(candidate->map_id) + ", not in map " +
                                                   std::to_string(query_map) + " (a merge, not a loop)"});
      continue;
    }
    std::string why;
    accepted = verify_place(map, query, candidate_id, /*drift_gate=*/true, why);
    if (!accepted) {
      result.rejected.push_back({candidate_id, why});
      continue;
    }
    accepted_kf = candidate_id;
    break;
  }
  result.timings.verification_ms = ms_since(verification_start);
  if (!accepted) return result;

  const auto correction_start = Clock::now();
  LoopCandidate loop;
  loop.loop_kf = query;
  loop.matched_kf = accepted_kf;
  loop.T_matched_loop = accepted->T_matched_loop;
  loop.matched_points = accepted->matched_points;
  LoopCorrectionOutput output = LoopCorrectionBuilder(options_.correction).compute(map, camera_, loop, loop_edges_);
  result.timings.correction_ms = ms_since(correction_start);
  if (!output.error.empty()) {
    result.rejected.push_back({accepted_kf, "correction: " + output.error});
    return result;
  }
  result.loop_matches = accepted->matches;
  result.correction = std::move(output.correction);
  loop_edges_.emplace_back(query, accepted_kf);
  detector_->loop_closed(query);
  return result;
}

LoopClosingResult LoopClosing::process_merge(const Map& map, KeyframeId query) {
  LoopClosingResult result;
  const Keyframe* query_kf = map.keyframe(query);
  if (!options_.merging || query_kf == nullptr || query_kf->culled) return result;
  const MapId active = query_kf->map_id;
  std::set<KeyframeId> other_maps;
  for (const auto& [id, kf] : map.keyframes) {
    if (!kf.culled && kf.map_id != active) other_maps.insert(other_maps.end(), id);
  }
  if (other_maps.empty()) return result;  // one map: nothing to merge (the common case, no cost)
  const auto detection_start = Clock::now();
  result.candidates = detector_->detect_merge(map, query, other_maps);
  result.timings.detection_ms = ms_since(detection_start);
  // The detector's confirmed candidates first, then those it has not confirmed yet (spatial check below).
  std::vector<std::pair<KeyframeId, bool>> to_verify;
  for (const KeyframeId id : result.candidates.keyframes) to_verify.emplace_back(id, true);
  for (const KeyframeId id : result.candidates.unconfirmed) to_verify.emplace_back(id, false);
  for (const auto& [candidate_id, confirmed] : to_verify) {
    const auto verification_start = Clock::now();
    std::string why;
    const std::optional<VerifiedPlace> place = verify_place(map, query, candidate_id, /*drift_gate=*/false, why);
    // The share of the predicted points found, for every verified candidate: a look-alike place's figure
    // is in the debug log of its rejection whichever test refuses it first.
    std::string found;
    const bool look_alike = place && found_share_too_low(map, *query_kf, candidate_id, place->T_matched_loop, found);
    if (place && place->matches >= options_.merge.min_matches && !look_alike && !confirmed) {
      why = confirm_in_space(map, *query_kf, candidate_id, place->T_matched_loop);
    }
    result.timings.verification_ms += ms_since(verification_start);
    if (!place) {
      result.rejected.push_back({candidate_id, "merge: " + why});
      continue;
    }
    if (place->matches < options_.merge.min_matches) {
      result.rejected.push_back({candidate_id, "merge: " + std::to_string(place->matches) + " matches (< " +
                                                   std::to_string(options_.merge.min_matches) + "); " + found});
      continue;
    }
    if (look_alike) {
      result.rejected.push_back({candidate_id, "merge: a look-alike place: " + found});
      continue;
    }
    if (!why.empty()) {
      result.rejected.push_back({candidate_id, "merge: " + why});
      continue;
    }
    const MapId matched = map.keyframe(candidate_id)->map_id;
    MapMergeRequest request;
    request.active_kf = query;
    request.matched_kf = candidate_id;
    request.T_matched_active = place->T_matched_loop;
    request.matched_points = place->matched_points;
    std::int64_t active_first_ns = std::numeric_limits<std::int64_t>::max();
    std::int64_t matched_first_ns = std::numeric_limits<std::int64_t>::max();
    for (const auto& [id, kf] : map.keyframes) {
      if (kf.map_id == active) {
        request.active_map.insert(request.active_map.end(), id);
        active_first_ns = std::min(active_first_ns, kf.stamp_ns);
      }
      if (kf.map_id == matched) {
        request.matched_map.insert(request.matched_map.end(), id);
        matched_first_ns = std::min(matched_first_ns, kf.stamp_ns);
      }
    }
    // The older map stays where it is and the newer one moves into it (map_merge.hpp). After a loss the
    // query's map is the newer one; the query's map is the older when an agent recognises another agent's
    // newer map, or when a frame relocalized in an older map of its own: then the matched map moves, seen
    // from the matched keyframe (the transform inverted, the point pairs turned round).
    if (older_map(active, active_first_ns, matched, matched_first_ns)) {
      std::swap(request.active_kf, request.matched_kf);
      std::swap(request.active_map, request.matched_map);
      request.T_matched_active = request.T_matched_active.inverse();
      for (auto& [active_point, matched_point] : request.matched_points) std::swap(active_point, matched_point);
    }
    const auto merge_start = Clock::now();
    MapMergeOutput merged = MapMerge(options_.merge).compute(map, camera_, request, loop_edges_);
    result.timings.merge_ms += ms_since(merge_start);
    result.merge_stats = merged.stats;
    if (!merged.error.empty()) {
      result.rejected.push_back({candidate_id, merged.error});
      continue;
    }
    result.loop_matches = place->matches;
    result.merge_found = found;
    result.merged_map = map.keyframe(request.active_kf)->map_id;
    result.into_map = map.keyframe(request.matched_kf)->map_id;
    result.correction = std::move(merged.correction);
    loop_edges_.emplace_back(query, candidate_id);
    detector_->maps_merged(query);
    break;
  }
  return result;
}

std::string LoopClosing::confirm_in_space(const Map& map, const Keyframe& query, KeyframeId candidate_id,
                                          const Pose3& T_matched_query) const {
  const Keyframe& candidate = *map.keyframe(candidate_id);
  const Pose3 T_BA = candidate.T_wc * T_matched_query * query.T_wc.inverse();
  const std::vector<KeyframeId> group = covisible_group(candidate);
  ProjectionMatchOptions projection;
  projection.radius_px = options_.projection_radius_px;
  projection.max_descriptor_distance = options_.matching.descriptor_threshold_low;
  constexpr int kLookedAt = 5;  // the query's best covisible keyframes (ORB-SLAM3: 5)
  int looked_at = 0;
  int confirmations = 0;
  std::string counts;
  for (const auto& [neighbour, weight] : query.covisible) {
    const Keyframe* kf = map.keyframe(neighbour);
    if (kf == nullptr || kf->culled || kf->map_id != query.map_id) continue;
    if (looked_at++ == kLookedAt || confirmations == options_.merge.covisible_confirmations) break;
    const int matches = projection_matches(map, *kf, T_BA * kf->T_wc, group, camera_, projection);
    counts += (counts.empty() ? "" : ", ") + std::to_string(matches);
    if (matches >= options_.merge.confirmation_matches) ++confirmations;
  }
  if (confirmations >= options_.merge.covisible_confirmations) return {};
  return "not consistent yet: " + std::to_string(confirmations) +
         " of the query's covisible keyframes see the place (< " +
         std::to_string(options_.merge.covisible_confirmations) + "; projection matches " +
         (counts.empty() ? std::string("none") : counts) +
         ", >= " + std::to_string(options_.merge.confirmation_matches) + " each)";
}

bool LoopClosing::found_share_too_low(const Map& map, const Keyframe& query, KeyframeId candidate_id,
                                      const Pose3& T_matched_query, std::string& figures) const {
  const Keyframe& candidate = *map.keyframe(candidate_id);
  ProjectionMatchOptions projection;
  projection.radius_px = options_.projection_radius_px;
  projection.max_descriptor_distance = options_.matching.descriptor_threshold_low;
  // The candidate's group seen from the query placed in the candidate's map, and the query's group seen
  // from the candidate placed in the query's map.
  int in_view_of_query = 0, in_view_of_candidate = 0;
  const int found_in_query = projection_matches(map, query, candidate.T_wc * T_matched_query,
                                                covisible_group(candidate), camera_, projection, &in_view_of_query);
  const int found_in_candidate = projection_matches(map, candidate, query.T_wc * T_matched_query.inverse(),
                                                    covisible_group(query), camera_, projection, &in_view_of_candidate);
  const int found = found_in_query + found_in_candidate;
  const int in_view = in_view_of_query + in_view_of_candidate;
  const double share = in_view > 0 ? static_cast<double>(found) / in_view : 0.0;
  char text[200];
  std::snprintf(text, sizeof text,
                "%d of the %d points predicted in view found (%.1f %%: %d of %d, %d of %d; >= %.1f %%)", found, in_view,
                100.0 * share, found_in_query, in_view_of_query, found_in_candidate, in_view_of_candidate,
                100.0 * options_.merge.min_found_share);
  figures = text;
  return share < options_.merge.min_found_share;
}

std::optional<LoopCorrection> LoopClosing::global_bundle_adjustment(const Map& map, const std::atomic<bool>* abort,
                                                                    const GlobalInertialInput* inertial,
                                                                    GlobalBundleAdjustmentStats* stats) const {
  GlobalBundleAdjustmentResult adjusted = GlobalBundleAdjustment().compute(map, camera_, abort, inertial);
  if (stats != nullptr) *stats = adjusted.stats;
  if (adjusted.stats.aborted) return std::nullopt;
  LoopCorrection correction;
  correction.kind = CorrectionKind::kGlobalBundleAdjustment;
  correction.map_version = map.version;
  correction.corrected_T_wc = std::move(adjusted.corrected_T_wc);
  correction.corrected_points = std::move(adjusted.p_w);
  return correction;
}

}  // namespace heslam
