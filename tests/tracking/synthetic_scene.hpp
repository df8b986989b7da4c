// A synthetic stereo world for tracker tests: 3D points with fixed descriptors, a smooth camera
// trajectory, and per-frame StereoFeatures made by projecting the points with pixel noise.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/feature/features.hpp"
#include "components/core/geometry/pose.hpp"

namespace heslam::test {

struct SyntheticPoint {
  Eigen::Vector3d p_w;
  Descriptor descriptor{};
  int octave = 0;
  float angle_deg = 0.f;
};

inline PinholeStereo synthetic_camera() {
  PinholeStereo camera;
  camera.fx_px = 450.0;
  camera.fy_px = 450.0;
  camera.cx_px = 320.0;
  camera.cy_px = 240.0;
  camera.baseline_m = 0.11;
  camera.width_px = 640;
  camera.height_px = 480;
  return camera;
}

inline Descriptor random_descriptor(std::mt19937_64& rng) {
  Descriptor d{};
  for (std::size_t i = 0; i < d.size(); i += 8) {
    const std::uint64_t word = rng();
    for (std::size_t b = 0; b < 8; ++b) d[i + b] = static_cast<std::uint8_t>(word >> (8 * b));
  }
  return d;
}

// Uniform in [0, 1) from the raw generator output (no distribution objects: portable sequences).
inline double uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

inline double gaussian(std::mt19937_64& rng) {
  // Box-Muller; guards log(0).
  const double u1 = std::max(uniform01(rng), 1e-12);
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Points in a slab 2..6 m in front of the start pose (world z), wide enough for the whole trajectory.
inline std::vector<SyntheticPoint> make_points(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<SyntheticPoint> points(static_cast<std::size_t>(count));
  for (auto& p : points) {
    p.p_w = Eigen::Vector3d(-5.0 + 10.0 * uniform01(rng), -3.5 + 7.0 * uniform01(rng), 2.0 + 4.0 * uniform01(rng));
    p.descriptor = random_descriptor(rng);
    const double r = uniform01(rng);
    p.octave = r < 0.5 ? 0 : r < 0.75 ? 1 : r < 0.9 ? 2 : 3;
    p.angle_deg = static_cast<float>(360.0 * uniform01(rng));
  }
  return points;
}

// Camera to world at frame k: a wobbling sideways / forward motion with some yaw and pitch (20 Hz).
inline Pose3 trajectory_pose(int k) {
  const double t = 0.05 * k;
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(1.5 * std::sin(0.8 * t), 0.15 * std::sin(1.7 * t), 0.6 * std::sin(0.5 * t));
  T.linear() = (Eigen::AngleAxisd(0.5 * std::sin(0.6 * t), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(0.08 * std::sin(1.1 * t), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

struct SyntheticFrameOptions {
  double pixel_noise_px = 0.3;   // at octave 0, scaled by the octave's scale (FAST corners: ~0.3 px)
  int descriptor_bit_flips = 6;  // per observation
  int clutter_keypoints = 80;    // random unmatched keypoints with random descriptors
};

inline StereoFeatures make_frame(const std::vector<SyntheticPoint>& points, const PinholeStereo& camera,
                                 const Pose3& T_wc, std::uint64_t seed, const SyntheticFrameOptions& options = {}) {
  std::mt19937_64 rng(seed);
  StereoFeatures f;
  const Pose3 T_cw = T_wc.inverse();
  for (const SyntheticPoint& p : points) {
    const Eigen::Vector3d p_c = T_cw * p.p_w;
    if (p_c.z() < 0.5) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    const double margin = 10.0;
    if (uv.x() < margin || uv.y() < margin || uv.x() > camera.width_px - margin || uv.y() > camera.height_px - margin) {
      continue;
    }
    const double sigma = options.pixel_noise_px * f.pyramid.scale[static_cast<std::size_t>(p.octave)];
    Keypoint kp;
    kp.u_px = static_cast<float>(uv.x() + sigma * gaussian(rng));
    kp.v_px = static_cast<float>(uv.y() + sigma * gaussian(rng));
    kp.octave = p.octave;
    kp.angle_deg = p.angle_deg;
    kp.response = 1.f;
    Descriptor d = p.descriptor;
    for (int b = 0; b < options.descriptor_bit_flips; ++b) {
      const std::uint64_t bit = rng() % 256;
      d[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    }
    const float ur = static_cast<float>(camera.u_right(p_c) + sigma * gaussian(rng));
    f.keypoints.push_back(kp);
    f.descriptors.push_back(d);
    const float disparity = kp.u_px - ur;
    if (disparity > 0.5f) {
      f.u_right_px.push_back(ur);
      f.depth_m.push_back(static_cast<float>(camera.bf() / disparity));
    } else {
      f.u_right_px.push_back(kNoStereo);
      f.depth_m.push_back(kNoStereo);
    }
  }
  for (int c = 0; c < options.clutter_keypoints; ++c) {
    Keypoint kp;
    kp.u_px = static_cast<float>(camera.width_px * uniform01(rng));
    kp.v_px = static_cast<float>(camera.height_px * uniform01(rng));
    kp.angle_deg = static_cast<float>(360.0 * uniform01(rng));
    f.keypoints.push_back(kp);
    f.descriptors.push_back(random_descriptor(rng));
    f.u_right_px.push_back(kNoStereo);
    f.depth_m.push_back(kNoStereo);
  }
  return f;
}

inline double rotation_error_deg(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.rotation().transpose() * b.rotation()).angle() * 180.0 / M_PI;
}

}  // namespace heslam::test
