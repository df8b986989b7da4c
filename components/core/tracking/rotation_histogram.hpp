// Orientation consistency of a set of matches: the keypoint angle differences of true matches agree
// (the whole image rotated by one angle), so only matches in the three fullest histogram bins are kept.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace heslam {

class RotationHistogram {
 public:
  static constexpr int kBins = 30;  // ORB-SLAM2 HISTO_LENGTH: 12-degree bins

  // `match` is any id the caller uses to undo the match (e.g. a keypoint index).
  void add(float angle_a_deg, float angle_b_deg, int match) {
    float rotation = angle_a_deg - angle_b_deg;
    if (rotation < 0.f) rotation += 360.f;
    int bin = static_cast<int>(std::lround(rotation * kBins / 360.f));
    if (bin == kBins) bin = 0;
    bins_[static_cast<std::size_t>(std::clamp(bin, 0, kBins - 1))].push_back(match);
  }

  // Matches outside the three largest bins (a bin under 10 % of the largest does not count), ascending.
  std::vector<int> rejected() const {
    std::array<std::size_t, 3> top{0, 0, 0};
    std::array<int, 3> top_bin{-1, -1, -1};
    for (int b = 0; b < kBins; ++b) {
      const std::size_t n = bins_[static_cast<std::size_t>(b)].size();
      if (n > top[0]) {
        top = {n, top[0], top[1]};
        top_bin = {b, top_bin[0], top_bin[1]};
      } else if (n > top[1]) {
        top = {top[0], n, top[1]};
        top_bin = {top_bin[0], b, top_bin[1]};
      } else if (n > top[2]) {
        top[2] = n;
        top_bin[2] = b;
      }
    }
    constexpr double kMinFractionOfBest = 0.1;
    for (int k = 1; k < 3; ++k) {
      if (static_cast<double>(top[k]) < kMinFractionOfBest * static_cast<double>(top[0])) top_bin[k] = -1;
    }
    std::vector<int> out;
    for (int b = 0; b < kBins; ++b) {
      if (b == top_bin[0] || b == top_bin[1] || b == top_bin[2]) continue;
      const auto& bin = bins_[static_cast<std::size_t>(b)];
      out.insert(out.end(), bin.begin(), bin.end());
    }
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  std::array<std::vector<int>, kBins> bins_;
};

}  // namespace heslam
