// Matches for triangulation between two keyframes: keypoints without a map point, compared by
// descriptor among those consistent with the epipolar geometry (ORB-SLAM2's SearchForTriangulation,
// without a vocabulary: every epipolar-consistent pair is a candidate).
#pragma once

#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"

namespace heslam {

// Fundamental matrix mapping a left-image point of kf1 to its epipolar line in kf2's left image:
// x2^T F21 x1 = 0 for homogeneous pixel coordinates.
Eigen::Matrix3d fundamental_21(const Pose3& T_wc1, const Pose3& T_wc2, const PinholeStereo& camera);

// One-to-one (index in kf1, index in kf2) pairs of unmatched keypoints with descriptor distance at
// most TH_LOW, the kf2 keypoint within chi2 of the epipolar line, and (optionally) rotation
// consistent with the dominant ones. Sorted by kf1 index.
std::vector<std::pair<int, int>> search_for_triangulation(const Keyframe& kf1, const Keyframe& kf2,
                                                          const PinholeStereo& camera,
                                                          const TriangulationOptions& options);

// Keeps matches whose keypoint rotation difference falls in the three most populated of 30 bins
// (ORB-SLAM2's rotation histogram). `rotation_deg[i]` belongs to `matches[i]`.
std::vector<std::pair<int, int>> keep_consistent_rotation(const std::vector<std::pair<int, int>>& matches,
                                                          const std::vector<float>& rotation_deg);

}  // namespace heslam
