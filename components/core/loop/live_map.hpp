// Small queries the loop correction and the map merge share: whether a keyframe or point is still in
// the map (not culled), and the milliseconds since a start for their timings.
#pragma once

#include <chrono>

#include "components/core/map/map.hpp"

namespace heslam::loop_detail {

using Clock = std::chrono::steady_clock;

inline double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

inline bool live_keyframe(const Map& map, KeyframeId id) {
  const Keyframe* kf = map.keyframe(id);
  return kf != nullptr && !kf->culled;
}

inline bool live_point(const Map& map, PointId id) {
  const MapPoint* point = map.point(id);
  return point != nullptr && !point->culled;
}

}  // namespace heslam::loop_detail
