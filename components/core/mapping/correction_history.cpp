// Corrections remembered for keyframes that predate them (see correction_history.hpp).
#include "components/core/mapping/correction_history.hpp"

#include <algorithm>

namespace heslam {

CorrectionMotion record_correction_motion(const std::map<KeyframeId, Pose3>& old_T_wc, const Map& map) {
  CorrectionMotion record;
  record.map_version = map.version;
  for (const auto& [id, T_old] : old_T_wc) {
    const Keyframe* kf = map.keyframe(id);
    if (kf == nullptr || kf->T_wc.matrix() == T_old.matrix()) continue;
    record.T_new_old.emplace(id, kf->T_wc * T_old.inverse());
  }
  return record;
}

Pose3 motion_of_late_keyframe(std::vector<CorrectionMotion>& history, KeyframeId kf, const TrackedAgainst& tracked) {
  Pose3 motion = Pose3::Identity();
  if (tracked.reference_kf == kNoId) return motion;
  for (CorrectionMotion& record : history) {
    if (record.map_version <= tracked.map_version) continue;  // the frontend had this correction
    const auto reference = record.T_new_old.find(tracked.reference_kf);
    if (reference == record.T_new_old.end()) continue;  // its reference did not move: neither does it
    const Pose3 step = reference->second;
    motion = step * motion;
    record.T_new_old[kf] = step;
  }
  return motion;
}

void forget_corrections_up_to(std::vector<CorrectionMotion>& history, std::uint64_t map_version) {
  history.erase(std::remove_if(history.begin(), history.end(),
                               [&](const CorrectionMotion& record) { return record.map_version <= map_version; }),
                history.end());
}

}  // namespace heslam
