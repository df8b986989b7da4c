// Keyframes that predate a loop correction the mapper already applied.
//
// In real time the frontend goes on tracking against its uncorrected mirror while a correction is
// computed and applied; a keyframe it makes meanwhile reaches the mapper after the correction and
// is in the old frame. The mapper remembers, per applied correction, the map version it produced
// and how it moved each keyframe (the world motion T_new T_old^-1). A keyframe tracked at an older
// map version is moved with the keyframe it was tracked against:
//   T_new(kf) = T_new(ref) T_old(ref)^-1 T_old(kf),
// and so are the points it creates; several corrections compose in the order they were applied.
// The keyframe's motion is added to each record it went through, so a keyframe tracked against it
// (also in flight) follows it. A reference the correction did not move leaves the keyframe as it is.
#pragma once

#include <cstdint>
#include <map>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"

namespace heslam {

// What a keyframe was tracked against (Keyframe sample: reference_keyframe_id, tracked_map_version).
struct TrackedAgainst {
  KeyframeId reference_kf = kNoId;  // kNoId: unknown, the keyframe is inserted as it comes
  std::uint64_t map_version = 0;    // the mapper's map version the frontend's mirror held completely
};

// One applied correction.
struct CorrectionMotion {
  std::uint64_t map_version = 0;          // the map version applying it produced
  std::map<KeyframeId, Pose3> T_new_old;  // per moved keyframe: T_new(kf) T_old(kf)^-1 (world)
};

// Records a correction just applied: `old_T_wc` are the poses before it, `map` the map after it
// (version already bumped). Keyframes whose pose did not change are not recorded.
CorrectionMotion record_correction_motion(const std::map<KeyframeId, Pose3>& old_T_wc, const Map& map);

// The world motion to apply to keyframe `kf` tracked as `tracked` (identity when no recorded
// correction is newer than its version or its reference moved in none), composed over `history`
// (oldest first). Adds kf's motion to every record it moved with.
Pose3 motion_of_late_keyframe(std::vector<CorrectionMotion>& history, KeyframeId kf, const TrackedAgainst& tracked);

// Drops the records no keyframe still in flight can predate: keyframes reach the mapper in id order
// and a frontend's mirror version never decreases, so once a keyframe tracked at version v arrived,
// corrections that produced v or older are behind every later keyframe.
void forget_corrections_up_to(std::vector<CorrectionMotion>& history, std::uint64_t map_version);

}  // namespace heslam
