// What one mapper step changed, so the process can publish states and disposals for exactly these.
#pragma once

#include <cstdint>
#include <map>
#include <set>

#include "components/core/map/map.hpp"

namespace heslam {

// Wall time per stage of one keyframe, milliseconds.
struct LocalMapperTimings {
  double insertion_ms = 0.0;
  double point_culling_ms = 0.0;
  double triangulation_ms = 0.0;
  double fusion_ms = 0.0;
  double bundle_adjustment_ms = 0.0;
  double bundle_adjustment_cpu_ms = 0.0;  // CPU time of the mapping thread in the local BA (load-independent)
  double keyframe_culling_ms = 0.0;
  double total_ms = 0.0;
};

// Counts of what happened, for logs and status.
struct LocalMapperCounts {
  int rejected_observations = 0;  // keyframe referenced an unknown / culled point
  int culled_points = 0;
  int triangulated_points = 0;
  int fused_points = 0;  // duplicates merged or observations added by fusion
  int bundle_adjustment_outliers = 0;
  // Size of the local BA's problem (its cost scales with these).
  int bundle_adjustment_free_keyframes = 0;
  int bundle_adjustment_fixed_keyframes = 0;
  int bundle_adjustment_points = 0;
  int bundle_adjustment_observations = 0;
  int culled_keyframes = 0;
  bool bundle_adjustment_aborted = false;
  bool inertial_bundle_adjustment = false;  // the local BA had IMU factors (LocalMapper::set_bundle_adjustment)
  int late_keyframes_moved = 0;             // tracked before a correction applied since: moved into its frame
};

struct MapChanges {
  std::uint64_t map_version = 0;              // version after the step
  std::set<KeyframeId> changed_keyframes;     // republish state (includes newly culled ones)
  std::set<PointId> changed_points;           // republish state
  std::map<PointId, PointId> removed_points;  // dispose: id -> merged_into (kNoId when culled)
  LocalMapperTimings timings;
  LocalMapperCounts counts;

  // Folds a later step into this one (e.g. several keyframes published together): sets are united,
  // a point removed later leaves changed_points, timings and counts are added.
  void merge(const MapChanges& other);
};

}  // namespace heslam
