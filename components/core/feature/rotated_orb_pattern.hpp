// The rBRIEF pattern (orb_pattern.hpp) rotated by a keypoint's angle, as pixel offsets into an image
// row-major with a given step: the two sample points of each of the 256 tests. Eight tests at a time
// with AVX2; the same offsets as the scalar formula ORB-SLAM2 and OpenCV use.
#pragma once

#include <array>

#include "components/core/feature/orb_pattern.hpp"

namespace heslam {

struct RotatedOrbPattern {
  alignas(32) std::array<int, kOrbPattern.size()> first;   // offset of the test's first point
  alignas(32) std::array<int, kOrbPattern.size()> second;  // offset of the test's second point
};

// Point (x, y) of the pattern goes to column x cos - y sin and row x sin + y cos, each rounded to
// the nearest integer (cvRound: ties to even); offset = row * step + column. Where the CPU has FMA
// (-march=native here) the first product of each sum is fused: fma(x, sin, y cos) and
// fma(x, cos, -(y sin)), which is what GCC made of the extractor's scalar formula before (C++ is
// compiled with -ffp-contract=fast; read from the disassembly), so descriptors stay bit-identical to
// that build's. Without FMA: plain products and sums.
void rotate_orb_pattern(float cos_angle, float sin_angle, int step, RotatedOrbPattern& out);

}  // namespace heslam
