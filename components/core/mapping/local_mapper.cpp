// The local mapper's per-keyframe pipeline and correction entry point.
#include "components/core/mapping/local_mapper.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "components/core/map/ids.hpp"
#include "components/core/mapping/correction_application.hpp"
#include "components/core/mapping/covisibility.hpp"
#include "components/core/mapping/keyframe_culling.hpp"
#include "components/core/mapping/local_bundle_adjustment.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_fusion.hpp"
#include "components/core/mapping/point_statistics.hpp"
#include "components/core/mapping/triangulation.hpp"

namespace heslam {
namespace {

// Corrections remembered for keyframes in flight: a keyframe is in flight for a fraction of a
// second, corrections come seconds apart; the bound only guards keyframes that never say what they
// were tracked against (then nothing is ever forgotten by version).
constexpr std::size_t kMaxRememberedCorrections = 16;

using Clock = std::chrono::steady_clock;

// CPU time of the calling thread: what a stage costs whatever else runs on the machine.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double ms_since(Clock::time_point& start) {
  const auto now = Clock::now();
  const double ms = std::chrono::duration<double, std::milli>(now - start).count();
  start = now;
  return ms;
}

// The recent points' ages in other agents' keyframes (LocalMapper::other_agents_keyframes_), which the map file
// does not hold, as they follow from it: the map's keyframes in the order they were processed (created_version)
// carry the counters keyframes_processed - n + 1 .. keyframes_processed, and each keyframe of another agent than
// a recent point's, processed after the point was made (recent_points: its counter), skipped it. A resumed
// mapper (a restart, a session) thus culls as the one that never stopped. One agent: empty.
std::map<PointId, std::uint64_t> other_agents_keyframes_of(const Map& map, const MapperState& state) {
  std::vector<std::pair<std::uint64_t, KeyframeId>> order;
  for (const auto& [id, version] : state.created_version) {
    if (map.keyframe(id) != nullptr) order.emplace_back(version, id);
  }
  std::map<PointId, std::uint64_t> skipped;
  if (order.empty() || order.size() > state.keyframes_processed) return skipped;  // not a mapper's own state
  std::sort(order.begin(), order.end());
  const std::uint64_t first_counter = state.keyframes_processed - order.size() + 1;
  for (const auto& [point_id, made_at] : state.recent_points) {
    const MapPoint* point = map.point(point_id);
    if (point == nullptr) continue;
    const int agent = agent_of(point->reference_kf);
    std::uint64_t count = 0;
    for (std::size_t i = order.size(); i-- > 0 && first_counter + i > made_at;) {
      if (agent_of(order[i].second) != agent) ++count;
    }
    if (count > 0) skipped.emplace(point_id, count);
  }
  return skipped;
}

void check_keyframe(const Map& map, const Keyframe& kf) {
  const std::string name = "keyframe " + format_id(kf.id);
  if (kf.id == kNoId) throw std::invalid_argument("keyframe: id 0 is reserved for 'no keyframe'");
  if (map.keyframe(kf.id) != nullptr) throw std::invalid_argument(name + ": already in the map");
  const std::size_t n = kf.features.keypoints.size();
  if (kf.features.descriptors.size() != n || kf.features.u_right_px.size() != n || kf.features.depth_m.size() != n ||
      kf.point_ids.size() != n) {
    throw std::invalid_argument(name + ": keypoints, descriptors, u_right, depth and point_ids must have " +
                                std::to_string(n) + " entries each");
  }
  for (const Keypoint& kp : kf.features.keypoints) {
    if (kp.octave < 0 || kp.octave >= kf.features.pyramid.levels) {
      throw std::invalid_argument(name + ": keypoint octave " + std::to_string(kp.octave) + " outside the pyramid");
    }
  }
}

}  // namespace

LocalMapper::LocalMapper(const PinholeStereo& camera, const LocalMapperOptions& options)
    : camera_(camera), options_(options) {}

LocalMapper::LocalMapper(const PinholeStereo& camera, const LocalMapperOptions& options, MapSnapshot snapshot)
    : camera_(camera),
      options_(options),
      map_(std::move(snapshot.map)),
      state_(std::move(snapshot.state)),
      other_agents_keyframes_(other_agents_keyframes_of(map_, state_)) {
  for (const auto& [id, kf] : map_.keyframes) maps_seen_.insert(kf.map_id);
}

PointId LocalMapper::resolve_merges(PointId id) const {
  // Merge chains are short; the bound guards a corrupt (cyclic) table.
  for (std::size_t hops = 0; hops <= state_.merged_into.size(); ++hops) {
    const auto it = state_.merged_into.find(id);
    if (it == state_.merged_into.end()) return id;
    id = it->second;
  }
  return kNoId;
}

void LocalMapper::insert_keyframe(Keyframe kf, std::vector<MapPoint> new_points, const TrackedAgainst& tracked,
                                  MapChanges& changes) {
  check_keyframe(map_, kf);
  // Made in a map a merge has folded into another since (a real-time frontend that had not heard of the
  // merge yet): it joins the map its reference keyframe went into, as its pose follows that keyframe below.
  if (tracked.reference_kf != kNoId && maps_seen_.count(kf.map_id) != 0) {
    const Keyframe* reference = map_.keyframe(tracked.reference_kf);
    const bool merged_away = std::none_of(map_.keyframes.begin(), map_.keyframes.end(),
                                          [&](const auto& entry) { return entry.second.map_id == kf.map_id; });
    if (reference != nullptr && reference->map_id != kf.map_id && merged_away) kf.map_id = reference->map_id;
  }
  maps_seen_.insert(kf.map_id);
  const KeyframeId kf_id = kf.id;
  const MapId map_id = kf.map_id;
  // Tracked before a correction applied since: into the corrected frame, with its reference.
  const Pose3 motion = motion_of_late_keyframe(state_.correction_motions, kf_id, tracked);
  if (!motion.matrix().isIdentity(0.0)) {
    kf.T_wc = motion * kf.T_wc;
    for (MapPoint& point : new_points) point.p_w = motion * point.p_w;
    changes.counts.late_keyframes_moved = 1;
  }
  if (tracked.reference_kf != kNoId) forget_corrections_up_to(state_.correction_motions, tracked.map_version);
  std::vector<PointId> references = std::move(kf.point_ids);
  kf.point_ids.assign(references.size(), kNoId);
  kf.parent = kNoId;
  kf.covisible.clear();
  kf.culled = false;
  map_.keyframes.emplace(kf_id, std::move(kf));
  state_.created_version[kf_id] = map_.version + 1;
  changes.changed_keyframes.insert(kf_id);

  std::vector<PointId> new_ids;
  for (MapPoint& point : new_points) {
    if (point.id == kNoId || map_.point(point.id) != nullptr || !point.p_w.allFinite()) {
      ++changes.counts.rejected_observations;
      continue;
    }
    point.observations.clear();
    point.map_id = map_id;  // a keyframe's new points are in its map
    point.reference_kf = kf_id;
    point.culled = false;
    point.merged_into = kNoId;
    state_.recent_points[point.id] = state_.keyframes_processed;
    new_ids.push_back(point.id);
    map_.points.emplace(point.id, std::move(point));
  }

  for (std::size_t i = 0; i < references.size(); ++i) {
    if (references[i] == kNoId) continue;
    const PointId id = resolve_merges(references[i]);
    MapPoint* point = map_.point(id);
    // The atlas: no observation crosses two maps (docs/topics.md, Map ids).
    if (point == nullptr || observation_index(*point, kf_id) >= 0 || point->map_id != map_id) {
      ++changes.counts.rejected_observations;
      continue;
    }
    add_observation(map_, id, kf_id, static_cast<int>(i));
    changes.changed_points.insert(id);
  }
  // Frontend points nobody references are dropped: they would be unobserved.
  for (const PointId id : new_ids) {
    if (!map_.points.at(id).observations.empty()) continue;
    state_.recent_points.erase(id);
    map_.points.erase(id);
    ++changes.counts.rejected_observations;
  }
  for (const PointId id : changes.changed_points) update_point_statistics(map_, id);
  for (const KeyframeId id : update_connections(map_, kf_id, options_.covisibility)) {
    changes.changed_keyframes.insert(id);
  }
}

void LocalMapper::cull_recent_points(KeyframeId current, MapChanges& changes) {
  const PointCullingOptions& o = options_.point_culling;
  const std::uint64_t now = state_.keyframes_processed;
  const int agent = agent_of(current);
  for (auto it = state_.recent_points.begin(); it != state_.recent_points.end();) {
    const MapPoint* point = map_.point(it->first);
    // Several agents: their keyframes interleave, and a point ages in the keyframes of its own agent only
    // (the agent of the keyframe it was made at). Counted against another agent's, a new agent's first
    // points were culled after two keyframes of the other one, before its second keyframe could see them.
    if (point != nullptr && agent_of(point->reference_kf) != agent) {
      ++other_agents_keyframes_[it->first];
      ++it;
      continue;
    }
    const auto skipped = other_agents_keyframes_.find(it->first);
    const std::uint64_t age = now - it->second - (skipped != other_agents_keyframes_.end() ? skipped->second : 0);
    bool erase_entry = false;
    if (point == nullptr) {
      erase_entry = true;
    } else if (point->visible > 0 &&
               static_cast<float>(point->found) < o.min_found_ratio * static_cast<float>(point->visible)) {
      erase_point(map_, it->first);
      changes.removed_points[it->first] = kNoId;
      ++changes.counts.culled_points;
      erase_entry = true;
    } else if (age >= static_cast<std::uint64_t>(o.keyframes_before_obs_check) &&
               observation_weight(map_, *point) <= o.min_observations) {
      erase_point(map_, it->first);
      changes.removed_points[it->first] = kNoId;
      ++changes.counts.culled_points;
      erase_entry = true;
    } else if (age >= static_cast<std::uint64_t>(o.keyframes_until_mature)) {
      erase_entry = true;
    }
    if (erase_entry) other_agents_keyframes_.erase(it->first);
    it = erase_entry ? state_.recent_points.erase(it) : std::next(it);
  }
}

void LocalMapper::record_removed(const MapChanges& changes) {
  for (const auto& [id, into] : changes.removed_points) {
    state_.recent_points.erase(id);
    other_agents_keyframes_.erase(id);
    if (into != kNoId) state_.merged_into[id] = into;
  }
}

void LocalMapper::refresh_culled_keyframes(MapChanges& changes) {
  std::map<KeyframeId, Pose3> resolved;
  std::function<Pose3(KeyframeId, int)> pose_of = [&](KeyframeId id, int depth) -> Pose3 {
    const Keyframe& kf = map_.keyframes.at(id);
    const auto relative = state_.culled_T_pc.find(id);
    if (relative == state_.culled_T_pc.end() || map_.keyframe(kf.parent) == nullptr ||
        depth > static_cast<int>(state_.culled_T_pc.size())) {
      return kf.T_wc;
    }
    if (auto it = resolved.find(id); it != resolved.end()) return it->second;
    const Pose3 T_wc = pose_of(kf.parent, depth + 1) * relative->second;
    resolved[id] = T_wc;
    return T_wc;
  };
  for (const auto& [id, T_pc] : state_.culled_T_pc) {
    Keyframe* kf = map_.keyframe(id);
    if (kf == nullptr) continue;
    const Pose3 T_wc = pose_of(id, 0);
    if (T_wc.matrix() != kf->T_wc.matrix()) {
      kf->T_wc = T_wc;
      changes.changed_keyframes.insert(id);
    }
  }
}

MapChanges LocalMapper::process_keyframe(Keyframe kf, std::vector<MapPoint> new_points, const TrackedAgainst& tracked) {
  MapChanges changes;
  const auto start = Clock::now();
  auto stage = start;
  ++state_.keyframes_processed;
  const KeyframeId kf_id = kf.id;
  try {
    insert_keyframe(std::move(kf), std::move(new_points), tracked, changes);
  } catch (...) {
    --state_.keyframes_processed;
    throw;
  }
  state_.last_keyframe = kf_id;
  changes.timings.insertion_ms = ms_since(stage);

  cull_recent_points(kf_id, changes);
  changes.timings.point_culling_ms = ms_since(stage);

  if (options_.enable_triangulation) {
    const auto created =
        create_new_points(map_, kf_id, camera_, options_.triangulation, kMapperTag, state_.next_point_counter);
    for (const PointId id : created) {
      state_.recent_points[id] = state_.keyframes_processed;
      changes.changed_points.insert(id);
    }
    changes.counts.triangulated_points = static_cast<int>(created.size());
  }
  changes.timings.triangulation_ms = ms_since(stage);

  if (options_.enable_fusion) {
    changes.counts.fused_points = fuse_with_neighbours(map_, kf_id, camera_, options_.fusion, changes);
  }
  for (const KeyframeId id : update_connections(map_, kf_id, options_.covisibility)) {
    changes.changed_keyframes.insert(id);
  }
  changes.timings.fusion_ms = ms_since(stage);

  if (options_.enable_bundle_adjustment) {
    const double cpu_start_ms = thread_cpu_ms();
    std::optional<LocalBundleAdjustmentResult> replaced;
    if (bundle_adjustment_) replaced = bundle_adjustment_(map_, kf_id, camera_, options_.bundle_adjustment, changes);
    changes.counts.inertial_bundle_adjustment = replaced.has_value();
    const LocalBundleAdjustmentResult ba =
        replaced ? *replaced : local_bundle_adjustment(map_, kf_id, camera_, options_.bundle_adjustment, changes);
    changes.timings.bundle_adjustment_cpu_ms = thread_cpu_ms() - cpu_start_ms;
    changes.counts.bundle_adjustment_outliers = ba.outliers_removed;
    changes.counts.bundle_adjustment_aborted = ba.aborted;
    changes.counts.bundle_adjustment_free_keyframes = ba.free_keyframes;
    changes.counts.bundle_adjustment_fixed_keyframes = ba.fixed_keyframes;
    changes.counts.bundle_adjustment_points = ba.points;
    changes.counts.bundle_adjustment_observations = ba.observations;
  }
  changes.timings.bundle_adjustment_ms = ms_since(stage);

  if (options_.enable_keyframe_culling) {
    const auto culled = cull_redundant_neighbours(map_, kf_id, camera_, options_.keyframe_culling, changes);
    for (const KeyframeId id : culled) {
      const Keyframe& culled_kf = map_.keyframes.at(id);
      const Keyframe* parent = map_.keyframe(culled_kf.parent);
      if (parent != nullptr) state_.culled_T_pc[id] = parent->T_wc.inverse() * culled_kf.T_wc;
    }
    changes.counts.culled_keyframes = static_cast<int>(culled.size());
  }
  refresh_culled_keyframes(changes);
  changes.timings.keyframe_culling_ms = ms_since(stage);

  record_removed(changes);
  for (const auto& [id, into] : changes.removed_points) changes.changed_points.erase(id);
  ++map_.version;
  changes.map_version = map_.version;
  changes.timings.total_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  return changes;
}

MapChanges LocalMapper::apply_correction(const LoopCorrection& correction) {
  MapChanges changes;
  const auto start = Clock::now();
  std::map<KeyframeId, Pose3> old_T_wc;
  for (const auto& [id, kf] : map_.keyframes) old_T_wc.emplace(id, kf.T_wc);
  apply_loop_correction(map_, correction, state_.created_version, changes);
  refresh_culled_keyframes(changes);
  record_removed(changes);
  for (const auto& [id, into] : changes.removed_points) changes.changed_points.erase(id);
  // Merges change which keyframes share points.
  std::set<KeyframeId> affected;
  for (const auto& [from, into] : correction.point_merges) {
    if (const MapPoint* point = map_.point(resolve_merges(into)); point != nullptr) {
      for (const auto& [kf_id, index] : point->observations) affected.insert(kf_id);
    }
  }
  for (const KeyframeId id : affected) {
    for (const KeyframeId touched : update_connections(map_, id, options_.covisibility)) {
      changes.changed_keyframes.insert(touched);
    }
  }
  ++map_.version;
  changes.map_version = map_.version;
  // Keyframes the frontend tracked before this version and sends later follow this correction.
  state_.correction_motions.push_back(record_correction_motion(old_T_wc, map_));
  if (state_.correction_motions.size() > kMaxRememberedCorrections) {
    state_.correction_motions.erase(state_.correction_motions.begin());
  }
  changes.timings.total_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  return changes;
}

MapFileWriteStats LocalMapper::save(const std::filesystem::path& path, bool sync) const {
  return save_map_file(path, map_, state_, sync, &camera_);
}

}  // namespace heslam
