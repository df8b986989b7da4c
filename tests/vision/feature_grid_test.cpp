// FeatureGrid: in_area returns exactly the brute-force answer (square window, octave limits).
#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "components/core/match/feature_grid.hpp"

namespace heslam {
namespace {

std::vector<int> brute_force(const std::vector<Keypoint>& kps, float u, float v, float r, int min_level,
                             int max_level) {
  std::vector<int> out;
  for (std::size_t i = 0; i < kps.size(); ++i) {
    if (min_level >= 0 && kps[i].octave < min_level) continue;
    if (max_level >= 0 && kps[i].octave > max_level) continue;
    if (std::abs(kps[i].u_px - u) < r && std::abs(kps[i].v_px - v) < r) out.push_back(static_cast<int>(i));
  }
  return out;
}

TEST(FeatureGrid, InAreaMatchesBruteForce) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(0.f, 751.99f), v(0.f, 479.99f);
  std::uniform_int_distribution<int> octave(0, 7);
  std::vector<Keypoint> kps(2000);
  for (Keypoint& k : kps) {
    k.u_px = u(rng);
    k.v_px = v(rng);
    k.octave = octave(rng);
  }
  const FeatureGrid grid(kps, 752, 480);
  EXPECT_EQ(grid.size(), kps.size());
  EXPECT_EQ(grid.cols(), 76);
  EXPECT_EQ(grid.rows(), 48);
  std::uniform_real_distribution<float> radius(0.5f, 60.f);
  for (int q = 0; q < 500; ++q) {
    const float qu = u(rng) * 1.1f - 30.f;  // also queries reaching past the borders
    const float qv = v(rng) * 1.1f - 20.f;
    const float r = radius(rng);
    const int min_level = q % 3 == 0 ? -1 : octave(rng);
    const int max_level = q % 4 == 0 ? -1 : std::max(min_level, octave(rng));
    EXPECT_EQ(grid.in_area(qu, qv, r, min_level, max_level), brute_force(kps, qu, qv, r, min_level, max_level));
  }
}

TEST(FeatureGrid, EmptyAndOutOfImage) {
  const FeatureGrid empty;
  EXPECT_TRUE(empty.in_area(10.f, 10.f, 5.f).empty());
  std::vector<Keypoint> kps(2);
  kps[0].u_px = -3.f;  // outside: clamped into the border cell, still found by a query reaching it
  kps[0].v_px = 5.f;
  kps[1].u_px = 100.f;
  kps[1].v_px = 100.f;
  const FeatureGrid grid(kps, 200, 200);
  EXPECT_EQ(grid.in_area(0.f, 5.f, 4.f), std::vector<int>{0});
  EXPECT_EQ(grid.in_area(100.f, 100.f, 0.5f), std::vector<int>{1});
  EXPECT_TRUE(grid.in_area(100.f, 100.f, 0.f).empty());
}

}  // namespace
}  // namespace heslam
