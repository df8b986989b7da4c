// Fusion of duplicated map points by projection (ORB-SLAM2's ORBmatcher::Fuse and
// LocalMapping::SearchInNeighbors): a point projected into a keyframe either becomes an observation
// of the matching keypoint or, if that keypoint already has a point, the two are merged.
#pragma once

#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "components/core/mapping/map_changes.hpp"
#include "components/core/match/feature_grid.hpp"

namespace heslam {

// Projects `point_ids` into keyframe `kf_id` (whose keypoints are indexed by `grid`) and fuses each
// with its best matching keypoint. Merged-away points are recorded in changes.removed_points, touched
// points in changes.changed_points. Returns the number of fused points.
int fuse_into_keyframe(Map& map, KeyframeId kf_id, const FeatureGrid& grid, const std::vector<PointId>& point_ids,
                       const PinholeStereo& camera, const FusionOptions& options, MapChanges& changes);

// SearchInNeighbors: fuses the new keyframe's points into its first- and second-order neighbours and
// theirs into it. Returns the number of fused points.
int fuse_with_neighbours(Map& map, KeyframeId kf_id, const PinholeStereo& camera, const FusionOptions& options,
                         MapChanges& changes);

}  // namespace heslam
