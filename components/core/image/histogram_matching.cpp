// Histogram matching: source quantiles looked up in the reference's inverse cdf.
#include "components/core/image/histogram_matching.hpp"

#include <algorithm>
#include <cmath>

namespace heslam {

GreyLut match_histogram(const GreyHistogram& source, const GreyHistogram& reference) {
  constexpr int kLevels = 256;
  GreyLut lut{};
  for (int v = 0; v < kLevels; ++v) lut[v] = static_cast<std::uint8_t>(v);
  std::uint64_t source_total = 0;
  std::uint64_t reference_total = 0;
  for (int v = 0; v < kLevels; ++v) {
    source_total += source[v];
    reference_total += reference[v];
  }
  if (source_total == 0 || reference_total == 0) return lut;

  // Walk both cdfs once: source levels in increasing order have increasing quantiles.
  const double scale = static_cast<double>(reference_total) / static_cast<double>(source_total);
  std::uint64_t source_below = 0;     // source pixels below level x
  std::uint64_t reference_below = 0;  // reference pixels below level y
  int y = 0;
  for (int x = 0; x < kLevels; ++x) {
    // The middle of x's cdf step, in reference pixel counts (an empty bin: the step's position).
    const double target = (static_cast<double>(source_below) + 0.5 * source[x]) * scale;
    source_below += source[x];
    while (y < kLevels - 1 && static_cast<double>(reference_below + reference[y]) < target) {
      reference_below += reference[y];
      ++y;
    }
    const double inside = reference[y] > 0 ? (target - static_cast<double>(reference_below)) / reference[y] : 0.5;
    const double level = static_cast<double>(y) - 0.5 + std::clamp(inside, 0.0, 1.0);
    lut[x] = static_cast<std::uint8_t>(std::clamp(std::lround(level), 0l, 255l));
  }
  return lut;
}

namespace {

// The lowest level of `histogram` at which the cdf reaches `count` pixels.
int level_at_count(const GreyHistogram& histogram, double count) {
  double cumulative = 0.0;
  for (int v = 0; v < 256; ++v) {
    cumulative += histogram[v];
    if (cumulative >= count) return v;
  }
  return 255;
}

}  // namespace

LinearTone fit_linear_tone(const GreyLut& curve, const GreyHistogram& source) {
  // Levels whose image is 3 or less / 250 or more sit on a clipped end of the curve.
  constexpr int kLowestFitted = 3;
  constexpr int kHighestFitted = 250;
  double weight = 0.0, sum_x = 0.0, sum_y = 0.0, sum_xx = 0.0, sum_xy = 0.0;
  int levels = 0;
  for (int x = 0; x < 256; ++x) {
    const double y = curve[x];
    if (source[x] == 0 || y < kLowestFitted || y > kHighestFitted) continue;
    const double w = source[x];
    weight += w;
    sum_x += w * x;
    sum_y += w * y;
    sum_xx += w * x * x;
    sum_xy += w * x * y;
    ++levels;
  }
  LinearTone line;
  const double determinant = weight * sum_xx - sum_x * sum_x;
  if (levels < 2 || !(determinant > 0.0)) return line;
  line.gain = (weight * sum_xy - sum_x * sum_y) / determinant;
  line.offset = (sum_y - line.gain * sum_x) / weight;
  return line;
}

StereoToneCurves align_stereo_tones(const GreyHistogram& left, const GreyHistogram& right, double saturation_excess,
                                    const LinearTone* measured) {
  StereoToneCurves curves;
  for (int v = 0; v < 256; ++v) curves.left[v] = static_cast<std::uint8_t>(v);
  curves.quantile = match_histogram(right, left);
  if (measured != nullptr) {
    for (int x = 0; x < 256; ++x) {
      curves.right[x] =
          static_cast<std::uint8_t>(std::clamp(std::lround(measured->gain * x + measured->offset), 0l, 255l));
    }
  } else {
    curves.right = curves.quantile;
  }
  double left_total = 0.0;
  double right_total = 0.0;
  for (int v = 0; v < 256; ++v) {
    left_total += left[v];
    right_total += right[v];
  }
  if (left_total == 0.0 || right_total == 0.0) return curves;

  // Right clipped at the top beyond the left: the left's top (same fraction) becomes one level.
  const double top_excess = right[255] / right_total - left[255] / left_total;
  if (top_excess > saturation_excess) {
    // With a measured relation, where it says the right saturates; else at the same quantile.
    const int ceiling =
        measured != nullptr
            ? static_cast<int>(std::clamp(std::lround(measured->gain * 255.0 + measured->offset), 1l, 255l))
            : level_at_count(left, (1.0 - right[255] / right_total) * left_total);
    for (int v = ceiling; v < 256; ++v) curves.left[v] = static_cast<std::uint8_t>(ceiling);
    curves.right[255] = static_cast<std::uint8_t>(ceiling);
    for (int v = 0; v < 255; ++v) curves.right[v] = std::min(curves.right[v], static_cast<std::uint8_t>(ceiling));
    curves.left_clipped = true;
  }
  // The same at the bottom (a right camera crushing its shadows to 0).
  const double bottom_excess = right[0] / right_total - left[0] / left_total;
  if (bottom_excess > saturation_excess) {
    const int floor = measured != nullptr ? static_cast<int>(std::clamp(std::lround(measured->offset), 0l, 254l))
                                          : level_at_count(left, right[0] / right_total * left_total);
    for (int v = 0; v <= floor; ++v) curves.left[v] = static_cast<std::uint8_t>(floor);
    curves.right[0] = static_cast<std::uint8_t>(floor);
    for (int v = 1; v < 256; ++v) curves.right[v] = std::max(curves.right[v], static_cast<std::uint8_t>(floor));
    curves.left_clipped = true;
  }
  double shift = 0.0;
  for (int v = 0; v < 256; ++v) shift += right[v] * std::abs(static_cast<int>(curves.right[v]) - v);
  curves.mean_right_shift = shift / right_total;
  return curves;
}

}  // namespace heslam
