// Accumulation of the changes of several mapper steps.
#include "components/core/mapping/map_changes.hpp"

#include <algorithm>

namespace heslam {

void MapChanges::merge(const MapChanges& other) {
  map_version = std::max(map_version, other.map_version);
  changed_keyframes.insert(other.changed_keyframes.begin(), other.changed_keyframes.end());
  for (const auto& [id, into] : other.removed_points) {
    removed_points[id] = into;
    changed_points.erase(id);
  }
  for (const PointId id : other.changed_points) {
    if (removed_points.count(id) == 0) changed_points.insert(id);
  }
  timings.insertion_ms += other.timings.insertion_ms;
  timings.point_culling_ms += other.timings.point_culling_ms;
  timings.triangulation_ms += other.timings.triangulation_ms;
  timings.fusion_ms += other.timings.fusion_ms;
  timings.bundle_adjustment_ms += other.timings.bundle_adjustment_ms;
  timings.bundle_adjustment_cpu_ms += other.timings.bundle_adjustment_cpu_ms;
  timings.keyframe_culling_ms += other.timings.keyframe_culling_ms;
  timings.total_ms += other.timings.total_ms;
  counts.rejected_observations += other.counts.rejected_observations;
  counts.culled_points += other.counts.culled_points;
  counts.triangulated_points += other.counts.triangulated_points;
  counts.fused_points += other.counts.fused_points;
  counts.bundle_adjustment_outliers += other.counts.bundle_adjustment_outliers;
  counts.bundle_adjustment_free_keyframes += other.counts.bundle_adjustment_free_keyframes;
  counts.bundle_adjustment_fixed_keyframes += other.counts.bundle_adjustment_fixed_keyframes;
  counts.bundle_adjustment_points += other.counts.bundle_adjustment_points;
  counts.bundle_adjustment_observations += other.counts.bundle_adjustment_observations;
  counts.culled_keyframes += other.counts.culled_keyframes;
  counts.late_keyframes_moved += other.counts.late_keyframes_moved;
  counts.bundle_adjustment_aborted = counts.bundle_adjustment_aborted || other.counts.bundle_adjustment_aborted;
  counts.inertial_bundle_adjustment = counts.inertial_bundle_adjustment || other.counts.inertial_bundle_adjustment;
}

}  // namespace heslam
