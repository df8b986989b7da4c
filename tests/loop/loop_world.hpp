// A synthetic loop for the loop-closing tests and benchmark: stereo keyframes on a circle (radius 2 m)
// looking out at a ring of textured points (radius 6 m), going round once and revisiting the start.
// Larger radii give longer loops with the same local structure (heslam-bench-loop). The map is
// built the way tracking would build it with odometry drift: poses chained from biased relative
// motions, a keyframe re-observes the points seen within the last few keyframes and creates new
// points (at its drifted pose) for the rest, so the revisit duplicates the first keyframes' points.
//
// Seeded and deterministic; world frame = camera convention (y down).
#pragma once

#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "components/core/loop/se3_ransac.hpp"
#include "components/core/mapping/covisibility.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"
#include "tests/mapping/synthetic_world.hpp"

namespace heslam::test {

struct LoopWorldOptions {
  int keyframes = 40;
  int keyframes_per_turn = 36;  // 10 deg apart: keyframes 36.. revisit 0..
  int points = 2500;
  // Odometry drift per keyframe, mostly rotational as in visual odometry. A bias (not a random walk)
  // is also in the covisibility edges, which then hold the essential graph away from the truth in
  // the middle of the loop: ~7 cm at 0.006 rad, ~5 cm at 0.004 rad (measured).
  double yaw_bias_rad = 0.004;
  Eigen::Vector3d translation_bias_m{0.002, 0.0005, 0.001};
  double pixel_noise_px = 0.5;  // keypoint noise at level 0 (the disparity's is half of it)
  int track_window = 6;         // a point not seen for this many keyframes is lost (re-created)
  unsigned seed = 11;
  double camera_radius_m = 2.0;  // the keyframes' circle (the revisit runs 5 cm further out)
  double ring_radius_m = 6.0;    // the points' ring
  // When not empty, world point i takes descriptor_pool[i % size] (e.g. ORB descriptors of real
  // images, so that a vocabulary sees realistic words) instead of random bytes.
  std::vector<Descriptor> descriptor_pool;
};

struct LoopWorld {
  SyntheticWorld world;
  Map map;
  std::map<KeyframeId, Pose3> true_T_wc;
  std::map<PointId, int> truth_of_point;                     // world point index
  std::map<KeyframeId, std::vector<int>> truth_of_keypoint;  // per keypoint: world point or -1
};

inline KeyframeId loop_kf_id(int k) { return static_cast<KeyframeId>(k + 1); }

inline Pose3 ring_pose(int k, int per_turn, double camera_radius_m = 2.0) {
  const double theta = 2.0 * M_PI * k / per_turn;
  const double radius_m = k >= per_turn ? camera_radius_m + 0.05 : camera_radius_m;  // close, not identical
  Pose3 T_wc = Pose3::Identity();
  T_wc.linear() = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_wc.translation() = radius_m * Eigen::Vector3d(std::sin(theta), 0.0, std::cos(theta));
  return T_wc;
}

inline LoopWorld make_loop_world(const LoopWorldOptions& options = {}) {
  LoopWorld result;
  SyntheticWorld& world = result.world;
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * M_PI);
  std::uniform_real_distribution<double> height(-1.5, 1.5);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> octave(0, 2);
  for (int i = 0; i < options.points; ++i) {
    const double a = angle(rng);
    world.points_w.emplace_back(options.ring_radius_m * std::sin(a), height(rng), options.ring_radius_m * std::cos(a));
    Descriptor d;
    for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
    const std::vector<Descriptor>& pool = options.descriptor_pool;
    if (!pool.empty()) d = pool[static_cast<std::size_t>(i) % pool.size()];
    world.descriptors.push_back(d);
    world.angles_deg.push_back(static_cast<float>(angle(rng) * 180.0 / M_PI));
    world.octaves.push_back(octave(rng));
  }

  Pose3 bias = Pose3::Identity();
  bias.linear() = Eigen::AngleAxisd(options.yaw_bias_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  bias.translation() = options.translation_bias_m;
  ViewOptions view_options;
  view_options.clutter = 20;
  view_options.pixel_noise_px = options.pixel_noise_px;
  std::map<int, PointId> point_of_truth;
  std::map<PointId, int> last_seen;
  std::uint64_t counter = 0;
  const auto true_pose = [&](int k) { return ring_pose(k, options.keyframes_per_turn, options.camera_radius_m); };
  Pose3 T_est = true_pose(0);
  for (int k = 0; k < options.keyframes; ++k) {
    const KeyframeId id = loop_kf_id(k);
    const Pose3 T_true = true_pose(k);
    if (k > 0) T_est = T_est * true_pose(k - 1).inverse() * T_true * bias;
    SyntheticView view = make_view(world, id, T_true, 500 + static_cast<unsigned>(k), view_options);
    view.kf.T_wc = T_est;
    view.kf.parent = k > 0 ? loop_kf_id(k - 1) : kNoId;
    result.true_T_wc[id] = T_true;
    result.truth_of_keypoint[id] = view.truth;
    result.map.keyframes.emplace(id, view.kf);
    const Keyframe& kf = result.map.keyframes.at(id);
    for (std::size_t i = 0; i < view.truth.size(); ++i) {
      const int t = view.truth[i];
      if (t < 0) continue;
      const auto tracked = point_of_truth.find(t);
      if (tracked != point_of_truth.end() && last_seen[tracked->second] >= k - options.track_window) {
        add_observation(result.map, tracked->second, id, static_cast<int>(i));
        last_seen[tracked->second] = k;
        continue;
      }
      if (!kf.features.has_stereo(i)) continue;
      MapPoint point;
      point.id = make_id(kFrontendTag, ++counter);
      const Keypoint& kp = kf.features.keypoints[i];
      point.p_w = T_est * world.camera.unproject(kp.u_px, kp.v_px, kf.features.depth_m[i]);
      point.reference_kf = id;
      result.map.points.emplace(point.id, point);
      add_observation(result.map, point.id, id, static_cast<int>(i));
      point_of_truth[t] = point.id;
      last_seen[point.id] = k;
      result.truth_of_point[point.id] = t;
    }
  }
  for (const auto& [id, point] : result.map.points) update_point_statistics(result.map, id);
  for (const auto& [id, kf] : result.map.keyframes) update_connections(result.map, id, CovisibilityOptions{});
  result.map.version = 7;
  return result;
}

// Correspondences between the stereo keypoints of two keyframes that see the same world point.
inline std::vector<Se3Correspondence> correspondences_between(const LoopWorld& w, KeyframeId a, KeyframeId b) {
  const Keyframe& kf_a = w.map.keyframes.at(a);
  const Keyframe& kf_b = w.map.keyframes.at(b);
  std::map<int, std::size_t> index_in_b;
  const std::vector<int>& truth_b = w.truth_of_keypoint.at(b);
  for (std::size_t j = 0; j < truth_b.size(); ++j) {
    if (truth_b[j] >= 0 && kf_b.features.has_stereo(j)) index_in_b[truth_b[j]] = j;
  }
  std::vector<Se3Correspondence> result;
  const std::vector<int>& truth_a = w.truth_of_keypoint.at(a);
  for (std::size_t i = 0; i < truth_a.size(); ++i) {
    const auto j = index_in_b.find(truth_a[i]);
    if (truth_a[i] < 0 || j == index_in_b.end() || !kf_a.features.has_stereo(i)) continue;
    const Keypoint& ka = kf_a.features.keypoints[i];
    const Keypoint& kb = kf_b.features.keypoints[j->second];
    Se3Correspondence c;
    c.uv_a_px = {ka.u_px, ka.v_px};
    c.uv_b_px = {kb.u_px, kb.v_px};
    c.p_a = w.world.camera.unproject(ka.u_px, ka.v_px, kf_a.features.depth_m[i]);
    c.p_b = w.world.camera.unproject(kb.u_px, kb.v_px, kf_b.features.depth_m[j->second]);
    c.sigma2_a = kf_a.features.pyramid.sigma2[static_cast<std::size_t>(ka.octave)];
    c.sigma2_b = kf_b.features.pyramid.sigma2[static_cast<std::size_t>(kb.octave)];
    result.push_back(c);
  }
  return result;
}

}  // namespace heslam::test
