// Application of a loop closer's correction to the map.
//
// Listed keyframes take their corrected pose. A keyframe created after the correction's map version
// (so unknown to the loop closer) follows its spanning-tree parent:
//   T_new(kf) = T_new(parent) T_old(parent)^-1 T_old(kf),
// applied from the root downwards so a chain of new keyframes moves rigidly with its corrected
// ancestor. Every map point moves with its reference keyframe, p_new = T_new(ref) T_old(ref)^-1 p_old.
// Listed corrected points then take their given positions (a global BA's or a merge's result). A merge
// (kind kMerge) then gives every keyframe and point of the loop keyframe's map the matched keyframe's
// map id. Finally the listed point merges are executed.
#pragma once

#include <cstdint>
#include <map>

#include "components/core/map/map.hpp"
#include "components/core/mapping/loop_correction.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

// `created_version[kf]` is the map version at which the mapper inserted kf; keyframes missing from
// it count as created before any correction. Unknown keyframes in the correction are skipped and
// counted in the return value (the correction is still applied to the rest).
int apply_loop_correction(Map& map, const LoopCorrection& correction,
                          const std::map<KeyframeId, std::uint64_t>& created_version, MapChanges& changes);

}  // namespace heslam
