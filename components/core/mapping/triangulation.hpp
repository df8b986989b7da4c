// New map points from keypoint pairs of the new keyframe and its best covisible keyframes
// (ORB-SLAM2's CreateNewMapPoints, stereo variant): ray or stereo point, whichever has the larger
// parallax, kept only with positive depth, small reprojection error in both views and a distance
// ratio consistent with the two keypoints' pyramid levels.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"

namespace heslam {

// Linear (DLT) triangulation of normalized image coordinates x = (X/Z, Y/Z) seen by two cameras
// with world->camera poses T_cw1, T_cw2. nullopt when the system is degenerate.
std::optional<Eigen::Vector3d> triangulate_linear(const Pose3& T_cw1, const Pose3& T_cw2, const Eigen::Vector2d& x1,
                                                  const Eigen::Vector2d& x2);

// The point from keypoint i1 of kf1 and i2 of kf2 if it passes every check, else nullopt.
std::optional<Eigen::Vector3d> triangulate_match(const Keyframe& kf1, int i1, const Keyframe& kf2, int i2,
                                                 const PinholeStereo& camera, const TriangulationOptions& options);

// Triangulates between `kf_id` and its best covisible keyframes; new points get ids
// make_id(creator_tag, ++next_counter) and are linked in both keyframes. Returns the new ids.
std::vector<PointId> create_new_points(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                       const TriangulationOptions& options, std::uint8_t creator_tag,
                                       std::uint64_t& next_counter);

}  // namespace heslam
