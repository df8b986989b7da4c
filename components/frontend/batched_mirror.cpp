// Mapper states applied per complete map version; own keyframes in flight follow a correction.
#include "components/frontend/batched_mirror.hpp"

#include <algorithm>

#include "runtime/sequence.hpp"

namespace heslam::frontend {

namespace {

void note_id(std::map<std::uint8_t, std::uint64_t>& largest, std::uint64_t id) {
  if (id == kNoId) return;
  std::uint64_t& counter = largest[creator_of(id)];
  counter = std::max(counter, counter_of(id));
}

std::uint64_t largest_of(const std::map<std::uint8_t, std::uint64_t>& largest, std::uint8_t tag) {
  const auto it = largest.find(tag);
  return it == largest.end() ? 0 : it->second;
}

}  // namespace

std::uint64_t BatchedMirror::largest_keyframe_counter(std::uint8_t tag) const {
  return largest_of(largest_keyframe_counter_, tag);
}
std::uint64_t BatchedMirror::largest_point_counter(std::uint8_t tag) const {
  return largest_of(largest_point_counter_, tag);
}

void BatchedMirror::add(const msg::KeyframeState& state) {
  note_id(largest_keyframe_counter_, state.id);
  if (messages::is_version_marker(state)) {
    markers_.keyframe_states = std::max(markers_.keyframe_states, state.map_version);
    if (state.correction_id != 0) correction_versions_.insert(state.map_version);
    return;
  }
  KeyframeStateCopy& copy = keyframe_states_[state.id];  // a newer state of a keyframe replaces the older
  copy.sample = state;
  const auto covisible = runtime::view(state.covisible);
  copy.covisible.assign(covisible.begin(), covisible.end());
  copy.sample.covisible = {};  // re-pointed at the copy when applied
}

void BatchedMirror::add(const msg::MapPointState& state) {
  note_id(largest_point_counter_, state.id);
  if (messages::is_version_marker(state)) {
    markers_.point_states = std::max(markers_.point_states, state.map_version);
    return;
  }
  PointStateCopy& copy = point_states_[state.id];
  copy.sample = state;
  const auto observations = runtime::view(state.observations);
  copy.observations.assign(observations.begin(), observations.end());
  for (const msg::PointObservation& observation : observations)
    note_id(largest_keyframe_counter_, observation.keyframe_id);
  copy.sample.observations = {};
  copy.disposed_after = false;
}

void BatchedMirror::dispose_point(PointId id) {
  if (id == messages::kVersionMarkerId) return;
  if (auto waiting = point_states_.find(id); waiting != point_states_.end()) {
    waiting->second.disposed_after = true;
    return;
  }
  // Nothing of it waits: flag it now (the tracker skips culled points; a later state revives it).
  pending_disposes_.insert(id);
}

bool BatchedMirror::correction_acknowledged(std::uint64_t map_version) {
  if (applied_corrections_.count(map_version) != 0) return true;
  if (map_version <= version_.complete()) return false;
  correction_versions_.insert(map_version);
  return true;
}

void BatchedMirror::own_keyframe(KeyframeId id, KeyframeId reference, std::uint64_t tracked_map_version) {
  in_flight_[id] = InFlight{reference, tracked_map_version};
}

BatchedMirror::Applied BatchedMirror::apply(Map& map) {
  Applied applied;
  version_.keyframe_states = std::max(version_.keyframe_states, markers_.keyframe_states);
  version_.point_states = std::max(version_.point_states, markers_.point_states);
  markers_ = messages::MirrorVersion{};
  const std::uint64_t complete = version_.complete();

  for (const PointId id : pending_disposes_) {
    messages::cull_point(map, id);
  }
  pending_disposes_.clear();

  std::uint64_t newest_correction = 0;
  for (auto it = correction_versions_.begin(); it != correction_versions_.end() && *it <= complete;) {
    newest_correction = *it;
    applied.correction = true;
    applied_corrections_.insert(*it);
    it = correction_versions_.erase(it);
  }

  std::map<KeyframeId, Pose3> old_T_wc;  // the keyframes a state is applied to, before it
  for (auto it = keyframe_states_.begin(); it != keyframe_states_.end();) {
    KeyframeStateCopy& copy = it->second;
    if (copy.sample.map_version > complete) {
      ++it;
      continue;
    }
    if (const Keyframe* keyframe = map.keyframe(it->first)) old_T_wc.emplace(it->first, keyframe->T_wc);
    runtime::borrow(copy.sample.covisible, copy.covisible);
    if (messages::apply_keyframe_state(map, copy.sample)) {
      ++applied.keyframe_states;
    } else {
      ++applied.unknown_keyframe_states;
    }
    in_flight_.erase(it->first);  // the mapper holds it: its states keep it up to date from now on
    it = keyframe_states_.erase(it);
  }
  // Merges after every other point state, as the mapper publishes them, each into the end of its
  // chain (a target merged in this batch too is gone by then): a keyframe slot then ends where the
  // mapper's does whatever the ids' order, and the applied map no longer depends on it.
  std::map<PointId, PointId> merged_into;
  for (const auto& [id, copy] : point_states_) {
    if (copy.sample.map_version <= complete && copy.sample.merged_into != kNoId)
      merged_into.emplace(id, copy.sample.merged_into);
  }
  const auto final_target = [&](PointId into) {
    for (std::size_t hops = 0; hops < merged_into.size(); ++hops) {
      const auto next = merged_into.find(into);
      if (next == merged_into.end() || next->second == into) break;
      into = next->second;
    }
    return into;
  };
  for (const bool merges : {false, true}) {
    for (auto it = point_states_.begin(); it != point_states_.end();) {
      PointStateCopy& copy = it->second;
      if (copy.sample.map_version > complete || (copy.sample.merged_into != kNoId) != merges) {
        ++it;
        continue;
      }
      if (merges) copy.sample.merged_into = final_target(copy.sample.merged_into);
      runtime::borrow(copy.sample.observations, copy.observations);
      messages::apply_point_state(map, copy.sample);
      ++applied.point_states;
      if (copy.disposed_after) {
        messages::cull_point(map, it->first);
      }
      it = point_states_.erase(it);
    }
  }
  if (applied.correction) move_keyframes_in_flight(map, old_T_wc, newest_correction, applied);
  return applied;
}

void BatchedMirror::move_keyframes_in_flight(Map& map, const std::map<KeyframeId, Pose3>& old_T_wc,
                                             std::uint64_t correction_version, Applied& applied) {
  // How the batch moved a keyframe (T_new T_old^-1, world), or nothing.
  std::map<KeyframeId, Pose3> moved;
  for (const auto& [id, T_old] : old_T_wc) {
    const Keyframe* keyframe = map.keyframe(id);
    if (keyframe != nullptr && keyframe->T_wc.matrix() != T_old.matrix())
      moved.emplace(id, keyframe->T_wc * T_old.inverse());
  }
  // Id order is creation order: a keyframe tracked against another one in flight follows it.
  for (const auto& [id, in_flight] : in_flight_) {
    if (in_flight.tracked_map_version >= correction_version) continue;  // tracked in the corrected map
    Keyframe* keyframe = map.keyframe(id);
    const auto reference = moved.find(in_flight.reference);
    if (keyframe == nullptr || reference == moved.end()) continue;
    const Pose3 motion = reference->second;
    keyframe->T_wc = motion * keyframe->T_wc;
    for (const PointId point_id : keyframe->point_ids) {
      MapPoint* point = map.point(point_id);
      if (point != nullptr && point->reference_kf == id) point->p_w = motion * point->p_w;
    }
    moved.emplace(id, motion);
    ++applied.keyframes_moved;
  }
}

}  // namespace heslam::frontend
