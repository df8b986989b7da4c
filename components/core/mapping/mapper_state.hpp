// Bookkeeping of the local mapper beyond the Map itself; persisted with the map so a restarted
// mapper continues exactly where it stopped.
#pragma once

#include <cstdint>
#include <map>

#include <vector>

#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/correction_history.hpp"

namespace heslam {

struct MapperState {
  std::uint64_t next_point_counter = 0;                 // last counter used for kMapperTag point ids
  std::uint64_t keyframes_processed = 0;                // keyframe sequence number (ids need not be contiguous)
  KeyframeId last_keyframe = kNoId;                     // the last keyframe processed (restart: what to skip)
  std::map<KeyframeId, std::uint64_t> created_version;  // map version at which a keyframe was inserted
  std::map<PointId, std::uint64_t> recent_points;       // young point -> keyframes_processed at creation
  std::map<KeyframeId, Pose3> culled_T_pc;              // culled keyframe relative to its parent
  std::map<PointId, PointId> merged_into;               // merged-away point -> the point it became
  // Applied corrections a keyframe still in flight may predate, oldest first (correction_history.hpp).
  std::vector<CorrectionMotion> correction_motions;
};

}  // namespace heslam
