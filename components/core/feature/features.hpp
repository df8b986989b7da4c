// Features of one rectified stereo frame: left keypoints, their rBRIEF descriptors and stereo depth.
//
// This is the hand-over point between the vision core (extraction, stereo matching) and everything
// that tracks or maps. Index i refers to the same keypoint in every vector.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

namespace heslam {

// 256-bit rotated BRIEF descriptor.
using Descriptor = std::array<std::uint8_t, 32>;

inline int hamming_distance(const Descriptor& a, const Descriptor& b) {
  int distance = 0;
  for (std::size_t i = 0; i < a.size(); i += 8) {
    std::uint64_t wa;
    std::uint64_t wb;
    std::memcpy(&wa, a.data() + i, 8);
    std::memcpy(&wb, b.data() + i, 8);
    distance += std::popcount(wa ^ wb);
  }
  return distance;
}

struct Keypoint {
  float u_px = 0.f;  // rectified left-image coordinates at level 0
  float v_px = 0.f;
  float angle_deg = 0.f;  // orientation by intensity centroid, [0, 360)
  float response = 0.f;   // FAST score
  int octave = 0;         // pyramid level the keypoint was detected on
};

// Scale pyramid constants, precomputed once (ORB-SLAM2: 8 levels x 1.2).
struct ScalePyramid {
  int levels = 8;
  float scale_factor = 1.2f;
  std::vector<float> scale;  // scale[l] = scale_factor^l
  std::vector<float> inv_scale;
  std::vector<float> sigma2;  // scale[l]^2: variance of a keypoint's position at level l
  std::vector<float> inv_sigma2;

  static ScalePyramid make(int levels, float scale_factor) {
    ScalePyramid p;
    p.levels = levels;
    p.scale_factor = scale_factor;
    float s = 1.f;
    for (int l = 0; l < levels; ++l) {
      p.scale.push_back(s);
      p.inv_scale.push_back(1.f / s);
      p.sigma2.push_back(s * s);
      p.inv_sigma2.push_back(1.f / (s * s));
      s *= scale_factor;
    }
    return p;
  }
};

inline constexpr float kNoStereo = -1.f;

struct StereoFeatures {
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;
  std::vector<float> u_right_px;  // kNoStereo where no stereo match
  std::vector<float> depth_m;     // kNoStereo where no stereo match
  // Per keypoint, or empty (= none): 1 where the stereo match's window touches a clip edge of a pair
  // whose cameras are exposed apart (match/clip_edge.hpp). Its depth still seeds map points; its
  // disparity, biased by where each camera's exposure put the edge, is trusted less in tracking.
  std::vector<std::uint8_t> near_clip;
  ScalePyramid pyramid = ScalePyramid::make(8, 1.2f);

  std::size_t size() const { return keypoints.size(); }
  bool has_stereo(std::size_t i) const { return depth_m[i] > 0.f; }
  bool stereo_near_clip(std::size_t i) const { return i < near_clip.size() && near_clip[i] != 0; }
};

}  // namespace heslam
