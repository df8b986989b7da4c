// ORB's keypoint orientation: the angle of the intensity centroid of a circular patch of radius 15
// around the keypoint (Rosin's moments m10 = sum u I(u, v), m01 = sum v I(u, v)), in exact integer
// arithmetic; one patch row pair per step with AVX2, the pixels multiplied by byte weights in pairs
// (pmaddubsw) without widening them (the same moments as the scalar sums).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace heslam {

class IntensityCentroid {
 public:
  // Radius of the patch (ORB's 31x31 patch).
  static constexpr int kRadiusPx = 15;

  IntensityCentroid();

  // The moments of the patch centred at `center` (8-bit image, row step `step` bytes). Reads rows
  // -15..15 and columns -15..16 around it (one column more than the patch: a 32-byte load).
  void moments(const std::uint8_t* center, std::ptrdiff_t step, int& m10, int& m01) const;

  // atan2(m01, m10) in degrees, in [0, 360).
  float angle_deg(const std::uint8_t* center, std::ptrdiff_t step) const;

  // Half width of the patch row at |v| (the circle: round(sqrt(15^2 - v^2))).
  int half_width(int v) const { return half_width_[static_cast<std::size_t>(v < 0 ? -v : v)]; }

 private:
  static constexpr int kRowBytes = 32;
  std::array<int, kRadiusPx + 1> half_width_{};
  // Per |v|: u for the columns of the patch row (u = column - 15), 0 outside it; and v inside it
  // (signed bytes: pmaddubsw's weights, |u|, v <= 15).
  alignas(32) std::array<std::array<std::int8_t, kRowBytes>, kRadiusPx + 1> u_weight_{};
  alignas(32) std::array<std::array<std::int8_t, kRowBytes>, kRadiusPx + 1> v_weight_{};
};

}  // namespace heslam
