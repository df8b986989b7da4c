// Synthetic stereo keyframes with known geometry for the mapping tests and benchmark: a room of
// textured walls, a camera moving on a circle inside it, keypoints as noisy projections of the
// room's points (plus clutter), and a minimal "frontend" that hands keyframes to the mapper the way
// the real one does (observations of existing points + new stereo points).
//
// World frame = camera convention (y down, z forward at the start); seeded, deterministic.
#pragma once

#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"

namespace heslam::test {

inline PinholeStereo euroc_like_camera() {
  PinholeStereo camera;
  camera.fx_px = 435.0;
  camera.fy_px = 435.0;
  camera.cx_px = 376.0;
  camera.cy_px = 240.0;
  camera.baseline_m = 0.11;
  camera.width_px = 752;
  camera.height_px = 480;
  return camera;
}

struct SyntheticWorld {
  PinholeStereo camera = euroc_like_camera();
  std::vector<Eigen::Vector3d> points_w;
  std::vector<Descriptor> descriptors;
  std::vector<float> angles_deg;
  std::vector<int> octaves;  // the pyramid level a point's texture is detected at (scale of the blob)
};

// Points uniformly on the four walls (|x| = half, |z| = half) and floor / ceiling (|y| = height/2).
inline SyntheticWorld make_room(int point_count, unsigned seed, double half_size_m = 3.0, double height_m = 3.0) {
  SyntheticWorld world;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> side(-half_size_m, half_size_m);
  std::uniform_real_distribution<double> up(-height_m / 2, height_m / 2);
  std::uniform_int_distribution<int> face(0, 5);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_real_distribution<float> angle(0.f, 360.f);
  for (int i = 0; i < point_count; ++i) {
    Eigen::Vector3d p;
    switch (face(rng)) {
      case 0: p = {half_size_m, up(rng), side(rng)}; break;
      case 1: p = {-half_size_m, up(rng), side(rng)}; break;
      case 2: p = {side(rng), up(rng), half_size_m}; break;
      case 3: p = {side(rng), up(rng), -half_size_m}; break;
      case 4: p = {side(rng), height_m / 2, side(rng)}; break;
      default: p = {side(rng), -height_m / 2, side(rng)}; break;
    }
    world.points_w.push_back(p);
    Descriptor d;
    for (auto& b : d) b = static_cast<std::uint8_t>(byte(rng));
    world.descriptors.push_back(d);
    world.angles_deg.push_back(angle(rng));
    world.octaves.push_back(std::uniform_int_distribution<int>(0, 2)(rng));
  }
  return world;
}

// Camera k on a circle of radius_m, yawing step_rad per keyframe (looking outwards-forwards).
inline Pose3 circle_pose(int k, double step_rad = 0.12, double radius_m = 0.6) {
  const double theta = k * step_rad;
  Pose3 T_wc = Pose3::Identity();
  T_wc.linear() = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_wc.translation() =
      Eigen::Vector3d(radius_m * std::sin(theta), 0.1 * std::sin(3 * theta), radius_m * std::cos(theta)) -
      Eigen::Vector3d(0, 0, radius_m);
  return T_wc;
}

struct ViewOptions {
  double pixel_noise_px = 0.5;  // per coordinate, level 0
  // Disparity noise over pixel noise. Our stereo matcher measures the disparity by SAD on a patch
  // around the LEFT keypoint, so the right coordinate is u - disparity: its error is the left
  // keypoint's plus an independent, smaller disparity error (the BA model, motion_only_ba.hpp).
  double disparity_noise_ratio = 0.5;
  double stereo_fraction = 1.0;  // share of keypoints with a stereo match
  double max_stereo_depth_m = 8.0;
  int max_octave = 2;        // keypoint octave = min(the point's octave, max_octave)
  int max_flipped_bits = 4;  // descriptor noise
  int clutter = 50;          // keypoints that are no world point
};

struct SyntheticView {
  Keyframe kf;             // features filled, point_ids all kNoId, T_wc = truth
  std::vector<int> truth;  // per keypoint: world point index, -1 for clutter
};

inline SyntheticView make_view(const SyntheticWorld& world, KeyframeId id, const Pose3& T_wc, unsigned seed,
                               const ViewOptions& options = {}) {
  SyntheticView view;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, options.pixel_noise_px);
  std::uniform_int_distribution<int> octave_of(0, options.max_octave);
  std::uniform_int_distribution<int> flips(0, options.max_flipped_bits);
  std::uniform_int_distribution<int> bit(0, 255);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const PinholeStereo& camera = world.camera;
  Keyframe& kf = view.kf;
  kf.id = id;
  kf.stamp_ns = static_cast<std::int64_t>(id) * 50'000'000;
  kf.T_wc = T_wc;
  StereoFeatures& f = kf.features;
  const Pose3 T_cw = T_wc.inverse();
  // disparity_true: bf / depth before noise.
  const auto add = [&](double u, double v, double disparity_true, double depth, int octave, const Descriptor& d,
                       float angle, int truth) {
    Keypoint kp;
    kp.u_px = static_cast<float>(u);
    kp.v_px = static_cast<float>(v);
    kp.octave = octave;
    kp.angle_deg = angle;
    kp.response = 1.f;
    f.keypoints.push_back(kp);
    f.descriptors.push_back(d);
    const bool stereo = depth > 0.0 && depth < options.max_stereo_depth_m && unit(rng) < options.stereo_fraction;
    const auto measured_disparity = [&] {
      return disparity_true +
             noise(rng) * options.disparity_noise_ratio * f.pyramid.scale[static_cast<std::size_t>(octave)];
    };
    f.u_right_px.push_back(stereo ? static_cast<float>(u - measured_disparity()) : kNoStereo);
    f.depth_m.push_back(stereo ? static_cast<float>(camera.bf() / (u - f.u_right_px.back())) : kNoStereo);
    view.truth.push_back(truth);
  };
  for (std::size_t i = 0; i < world.points_w.size(); ++i) {
    const Eigen::Vector3d p_c = T_cw * world.points_w[i];
    if (p_c.z() < 0.3) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    const int octave = std::min(world.octaves[i], options.max_octave);
    const double sigma = f.pyramid.scale[static_cast<std::size_t>(octave)];
    const double u = uv.x() + noise(rng) * sigma;
    const double v = uv.y() + noise(rng) * sigma;
    if (!camera.in_image(u, v) || !camera.in_image(u - camera.bf() / p_c.z(), v)) continue;
    Descriptor d = world.descriptors[i];
    for (int k = flips(rng); k > 0; --k) {
      const int b = bit(rng);
      d[static_cast<std::size_t>(b / 8)] ^= static_cast<std::uint8_t>(1u << (b % 8));
    }
    add(u, v, camera.bf() / p_c.z(), p_c.z(), octave, d, world.angles_deg[i], static_cast<int>(i));
  }
  for (int c = 0; c < options.clutter; ++c) {
    Descriptor d;
    for (auto& b : d) b = static_cast<std::uint8_t>(bit(rng));
    add(unit(rng) * (camera.width_px - 1), unit(rng) * (camera.height_px - 1), 0.0, -1.0, octave_of(rng), d,
        static_cast<float>(unit(rng) * 360.0), -1);
  }
  kf.point_ids.assign(f.size(), kNoId);
  return view;
}

// The frontend's side of the hand-over, emulated with ground truth: the keyframe observes every map
// point whose world point it sees (perfect tracking), and close stereo keypoints without a point
// become new frontend points, positioned from the keyframe's (estimated) pose and stereo depth.
class FrontendEmulator {
 public:
  explicit FrontendEmulator(const SyntheticWorld& world, double new_point_max_depth_m = 35 * 0.11)
      : world_(world), new_point_max_depth_m_(new_point_max_depth_m) {}

  // `view.kf.T_wc` is replaced by `T_wc_estimate`.
  std::pair<Keyframe, std::vector<MapPoint>> keyframe(const Map& map, const SyntheticView& view,
                                                      const Pose3& T_wc_estimate) {
    truth_of_kf_[view.kf.id] = view.truth;
    std::map<int, PointId> point_of_truth;
    for (const auto& [id, point] : map.points) {
      const int t = truth_of_point(point);
      if (t >= 0 && point_of_truth.count(t) == 0) point_of_truth[t] = id;
    }
    Keyframe kf = view.kf;
    kf.T_wc = T_wc_estimate;
    std::vector<MapPoint> new_points;
    for (std::size_t i = 0; i < kf.point_ids.size(); ++i) {
      const int t = view.truth[i];
      if (t < 0) continue;
      if (auto it = point_of_truth.find(t); it != point_of_truth.end()) {
        kf.point_ids[i] = it->second;
      } else if (kf.features.has_stereo(i) && kf.features.depth_m[i] < new_point_max_depth_m_) {
        MapPoint point;
        point.id = make_id(kFrontendTag, ++counter_);
        const Keypoint& kp = kf.features.keypoints[i];
        point.p_w = T_wc_estimate * world_.camera.unproject(kp.u_px, kp.v_px, kf.features.depth_m[i]);
        point.descriptor = kf.features.descriptors[i];
        kf.point_ids[i] = point.id;
        point_of_truth[t] = point.id;
        new_points.push_back(point);
      }
    }
    return {kf, new_points};
  }

  // World point index of a map point (via its first observation), -1 when unknown / clutter.
  int truth_of_point(const MapPoint& point) const {
    for (const auto& [kf_id, index] : point.observations) {
      const auto it = truth_of_kf_.find(kf_id);
      if (it != truth_of_kf_.end()) return it->second[static_cast<std::size_t>(index)];
    }
    return -1;
  }

 private:
  const SyntheticWorld& world_;
  double new_point_max_depth_m_;
  std::uint64_t counter_ = 0;
  std::map<KeyframeId, std::vector<int>> truth_of_kf_;
};

}  // namespace heslam::test
