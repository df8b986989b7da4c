// Derived state of a map point from its observations: representative descriptor, mean viewing
// direction and the distance range over which ORB can re-detect it (ORB-SLAM2's
// ComputeDistinctiveDescriptors and UpdateNormalAndDepth).
#pragma once

#include "components/core/map/map.hpp"

namespace heslam {

// Recomputes descriptor, normal and distance range; no-op for a point without observations.
void update_point_statistics(Map& map, PointId point_id);

// The observation's descriptor with the least median Hamming distance to the others.
Descriptor representative_descriptor(const Map& map, const MapPoint& point);

// Pyramid level at which a point at `distance_m` is expected to be detected (ORB-SLAM2
// PredictScale), clamped to the pyramid.
int predict_level(const MapPoint& point, double distance_m, const ScalePyramid& pyramid);

}  // namespace heslam
