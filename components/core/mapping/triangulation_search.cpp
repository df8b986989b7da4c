// Epipolar-constrained descriptor search between two keyframes.
#include "components/core/mapping/triangulation_search.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace heslam {
namespace {

constexpr int kRotationBins = 30;  // ORB-SLAM2 HISTO_LENGTH: 12 deg bins
constexpr int kKeptRotationBins = 3;

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Eigen::Matrix3d fundamental_21(const Pose3& T_wc1, const Pose3& T_wc2, const PinholeStereo& camera) {
  const Pose3 T_21 = T_wc2.inverse() * T_wc1;  // kf1 camera -> kf2 camera
  Eigen::Matrix3d K;
  K << camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1;
  const Eigen::Matrix3d K_inv = K.inverse();
  return K_inv.transpose() * skew(T_21.translation()) * T_21.linear() * K_inv;
}

std::vector<std::pair<int, int>> keep_consistent_rotation(const std::vector<std::pair<int, int>>& matches,
                                                          const std::vector<float>& rotation_deg) {
  std::array<std::vector<std::size_t>, kRotationBins> bins;
  for (std::size_t m = 0; m < matches.size(); ++m) {
    float rotation = std::fmod(rotation_deg[m], 360.f);
    if (rotation < 0.f) rotation += 360.f;
    const int bin = std::min(kRotationBins - 1, static_cast<int>(rotation * kRotationBins / 360.f));
    bins[static_cast<std::size_t>(bin)].push_back(m);
  }
  std::array<int, kRotationBins> order;
  for (int b = 0; b < kRotationBins; ++b) order[static_cast<std::size_t>(b)] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return bins[static_cast<std::size_t>(a)].size() > bins[static_cast<std::size_t>(b)].size();
  });
  // ORB-SLAM2 drops the 2nd / 3rd bins when they hold less than a tenth of the 1st.
  const std::size_t top = bins[static_cast<std::size_t>(order[0])].size();
  std::vector<bool> keep(matches.size(), false);
  for (int k = 0; k < kKeptRotationBins; ++k) {
    const auto& bin = bins[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])];
    if (k > 0 && bin.size() * 10 < top) break;
    for (const std::size_t m : bin) keep[m] = true;
  }
  std::vector<std::pair<int, int>> kept;
  for (std::size_t m = 0; m < matches.size(); ++m) {
    if (keep[m]) kept.push_back(matches[m]);
  }
  return kept;
}

std::vector<std::pair<int, int>> search_for_triangulation(const Keyframe& kf1, const Keyframe& kf2,
                                                          const PinholeStereo& camera,
                                                          const TriangulationOptions& options) {
  const Eigen::Matrix3d F21 = fundamental_21(kf1.T_wc, kf2.T_wc, camera);
  const auto& kps1 = kf1.features.keypoints;
  const auto& kps2 = kf2.features.keypoints;

  // The free keypoints of kf2 in flat arrays (position, epipolar threshold by octave): the
  // epipolar test over all of them is the inner loop of the search, and a branch-free pass over
  // contiguous doubles vectorises; the descriptor distance is then computed for the few that pass.
  std::vector<float> max_epipolar_sq(static_cast<std::size_t>(kf2.features.pyramid.levels));
  for (std::size_t l = 0; l < max_epipolar_sq.size(); ++l) {
    max_epipolar_sq[l] = options.epipolar_chi2 * kf2.features.pyramid.sigma2[l];
  }
  std::vector<int> free2;
  std::vector<double> u2, v2, threshold2;
  for (std::size_t j = 0; j < kps2.size(); ++j) {
    if (kf2.point_ids[j] != kNoId) continue;
    free2.push_back(static_cast<int>(j));
    u2.push_back(kps2[j].u_px);
    v2.push_back(kps2[j].v_px);
    threshold2.push_back(max_epipolar_sq[static_cast<std::size_t>(kps2[j].octave)]);
  }
  const std::size_t free_count = free2.size();
  std::vector<unsigned char> near_line(free_count);

  // Best kf1 candidate per kf2 keypoint: (distance, kf1 index); one-to-one by keeping the closest.
  std::vector<std::pair<int, int>> best_for2(kps2.size(), {std::numeric_limits<int>::max(), -1});
  for (std::size_t i = 0; i < kps1.size(); ++i) {
    if (kf1.point_ids[i] != kNoId) continue;
    const Eigen::Vector3d line = F21 * Eigen::Vector3d(kps1[i].u_px, kps1[i].v_px, 1.0);
    const double norm_sq = line.x() * line.x() + line.y() * line.y();
    if (norm_sq <= 0.0) continue;
    const double a = line.x(), b = line.y(), c = line.z();
    for (std::size_t k = 0; k < free_count; ++k) {
      const double num = a * u2[k] + b * v2[k] + c;
      near_line[k] = num * num < threshold2[k] * norm_sq;
    }
    const Descriptor& d1 = kf1.features.descriptors[i];
    int best_distance = options.max_descriptor_distance + 1;
    int best_j = -1;
    for (std::size_t k = 0; k < free_count; ++k) {
      if (!near_line[k]) continue;
      const int j = free2[k];
      const int distance = hamming_distance(d1, kf2.features.descriptors[static_cast<std::size_t>(j)]);
      if (distance < best_distance) {
        best_distance = distance;
        best_j = j;
      }
    }
    if (best_j < 0) continue;
    auto& slot = best_for2[static_cast<std::size_t>(best_j)];
    if (best_distance < slot.first) slot = {best_distance, static_cast<int>(i)};
  }

  std::vector<std::pair<int, int>> matches;
  std::vector<float> rotation;
  for (std::size_t j = 0; j < best_for2.size(); ++j) {
    if (best_for2[j].second < 0) continue;
    const int i = best_for2[j].second;
    matches.emplace_back(i, static_cast<int>(j));
    rotation.push_back(kps1[static_cast<std::size_t>(i)].angle_deg - kps2[j].angle_deg);
  }
  if (options.check_orientation) matches = keep_consistent_rotation(matches, rotation);
  std::sort(matches.begin(), matches.end());
  return matches;
}

}  // namespace heslam
