// Corrected poses, spanning-tree propagation, points moved with their reference keyframe, merges.
#include "components/core/mapping/correction_application.hpp"

#include <functional>
#include <set>
#include <unordered_map>

#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"

namespace heslam {

int apply_loop_correction(Map& map, const LoopCorrection& correction,
                          const std::map<KeyframeId, std::uint64_t>& created_version, MapChanges& changes) {
  int skipped = 0;
  std::set<PointId> observations_changed = changes.changed_points;
  std::map<KeyframeId, Pose3> old_T_wc;
  for (const auto& [id, kf] : map.keyframes) old_T_wc.emplace(id, kf.T_wc);

  std::map<KeyframeId, Pose3> new_T_wc;
  for (const auto& [id, T_wc] : correction.corrected_T_wc) {
    if (map.keyframe(id) == nullptr) {
      ++skipped;
      continue;
    }
    new_T_wc[id] = T_wc;
  }

  // Resolves a keyframe's new pose: corrected, propagated from its parent, or unchanged.
  std::map<KeyframeId, bool> in_progress;
  std::function<Pose3(KeyframeId)> resolve = [&](KeyframeId id) -> Pose3 {
    if (auto it = new_T_wc.find(id); it != new_T_wc.end()) return it->second;
    const Keyframe& kf = map.keyframes.at(id);
    const auto created = created_version.find(id);
    // Culled keyframes always ride on their parent: nobody else keeps them consistent.
    const bool after_version =
        kf.culled || (created != created_version.end() && created->second > correction.map_version);
    Pose3 result = old_T_wc.at(id);
    if (after_version && kf.parent != kNoId && map.keyframe(kf.parent) != nullptr && !in_progress[id]) {
      in_progress[id] = true;  // guards a (corrupt) cyclic tree
      const Pose3 parent_new = resolve(kf.parent);
      result = parent_new * old_T_wc.at(kf.parent).inverse() * old_T_wc.at(id);
    }
    new_T_wc[id] = result;
    return result;
  };
  for (const auto& [id, kf] : map.keyframes) resolve(id);

  for (auto& [id, kf] : map.keyframes) {
    const Pose3& T_new = new_T_wc.at(id);
    if (T_new.matrix() != kf.T_wc.matrix()) changes.changed_keyframes.insert(id);
    kf.T_wc = T_new;
  }
  // Per keyframe once: its old pose's inverse and new pose (a point moves as ref_new * (ref_old^-1 * p)).
  struct Motion {
    Pose3 old_inverse;
    const Pose3* new_T_wc;
  };
  std::unordered_map<KeyframeId, Motion> motion_of;
  motion_of.reserve(map.keyframes.size());
  for (const auto& [id, T_old] : old_T_wc) {
    const Pose3& T_new = new_T_wc.at(id);
    if (T_new.matrix() != T_old.matrix()) motion_of.emplace(id, Motion{T_old.inverse(), &T_new});
  }
  for (auto& [id, point] : map.points) {
    const auto motion = motion_of.find(point.reference_kf);
    if (motion == motion_of.end()) continue;  // unknown or unmoved reference keyframe
    point.p_w = *motion->second.new_T_wc * (motion->second.old_inverse * point.p_w);
    changes.changed_points.insert(changes.changed_points.end(), id);  // ids ascend: a hint, not a search
  }
  for (const auto& [id, p_w] : correction.corrected_points) {
    MapPoint* point = map.point(id);
    if (point == nullptr) {
      ++skipped;
      continue;
    }
    if (point->p_w == p_w) continue;
    point->p_w = p_w;
    changes.changed_points.insert(id);
  }

  // A merge: the loop keyframe's map becomes the matched keyframe's, keyframes the loop closer did not
  // know yet included (they were made in that map). Before the point merges, so fused points agree.
  if (correction.kind == CorrectionKind::kMerge) {
    const Keyframe* loop_kf = map.keyframe(correction.loop_kf);
    const Keyframe* matched_kf = map.keyframe(correction.matched_kf);
    if (loop_kf == nullptr || matched_kf == nullptr) {
      ++skipped;
    } else if (loop_kf->map_id != matched_kf->map_id) {
      const MapId merged = loop_kf->map_id;
      const MapId into = matched_kf->map_id;
      for (auto& [id, kf] : map.keyframes) {
        if (kf.map_id != merged) continue;
        kf.map_id = into;
        changes.changed_keyframes.insert(id);
      }
      for (auto& [id, point] : map.points) {
        if (point.map_id != merged) continue;
        point.map_id = into;
        changes.changed_points.insert(id);
      }
    }
  }

  for (const auto& [from, into] : correction.point_merges) {
    if (map.point(from) == nullptr || map.point(into) == nullptr || from == into) {
      ++skipped;
      continue;
    }
    replace_point(map, from, into);
    observations_changed.insert(into);
    changes.removed_points[from] = into;
    changes.changed_points.erase(from);
    changes.changed_points.insert(into);
  }
  // Both in id order: one walk over the points instead of a search per changed point. A point this
  // correction only moved keeps its observations, so only its normal and distance range change; a
  // merge's target, and whatever the caller had changed before, get their descriptor chosen again.
  const KeyframeIndex keyframes(map);
  auto point = map.points.begin();
  for (const PointId id : changes.changed_points) {
    while (point != map.points.end() && point->first < id) ++point;
    if (point == map.points.end() || point->first != id) continue;
    if (observations_changed.contains(id)) {
      update_point_statistics(point->second, keyframes);
    } else {
      update_point_geometry(point->second, keyframes);
    }
  }
  return skipped;
}

}  // namespace heslam
