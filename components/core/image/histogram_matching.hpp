// Histogram matching (specification) between the two images of a stereo pair: the monotonic tone
// curve that gives the source image the reference image's grey-level distribution. Both cameras see
// nearly the same scene, so this curve undoes whatever monotonic difference their exposures have
// (gain, offset, gamma, auto-exposure of one camera) without knowing its form; where the source is
// saturated, the whole saturated bin goes to one level of the reference's matching quantile range.
#pragma once

#include <array>
#include <cstdint>

namespace heslam {

using GreyHistogram = std::array<std::uint32_t, 256>;
using GreyLut = std::array<std::uint8_t, 256>;

// lut[x] = the reference's grey level at the quantile of the source's level x (the middle of the
// source bin's cdf step), interpolated inside the reference's bin as if its values were spread
// uniformly over [y - 0.5, y + 0.5]. The identity when both histograms are equal; empty source bins
// map monotonically too. An empty histogram on either side gives the identity.
GreyLut match_histogram(const GreyHistogram& source, const GreyHistogram& reference);

// The tone curves that bring a stereo pair to one photometry: `right` is the right image's histogram
// matched to the left's; and where the right camera clipped more of the scene than the left (a spike
// at 255, or at 0, holding more than `saturation_excess` of its pixels beyond the left's own), the
// left is clipped at the same quantile and both saturated parts go to that one level. Then the left
// image keeps no texture the right cannot show, so its features lie where stereo can give them depth
// (measured on EuRoC MH01 with the right camera at x4: docs/vision.md). A more clipped LEFT needs no
// extra step: the matching itself maps the right's corresponding levels onto the left's spike.
struct StereoToneCurves {
  GreyLut left{};
  GreyLut right{};
  // The right's histogram matched to the left's (match_histogram), before any measured line or
  // clipping: what fit_linear_tone reads to see the relation from the histograms.
  GreyLut quantile{};
  bool left_clipped = false;  // the left was clipped to the right's range
  // Mean |right[x] - x| over the right image's pixels, in grey levels: how far apart the cameras are.
  double mean_right_shift = 0.0;
};
//
// `measured`: the cameras' relation measured elsewhere (left ~ gain x right + offset, e.g. on the
// last pairs' stereo matches, stereo_tone.hpp); the right's curve is then that line, clamped to
// [0, 255], instead of the quantile curve, and a left clipped to the right's range is clipped where
// the line puts the right's 255 (its 0) instead of at the same quantile.
struct LinearTone {
  double gain = 1.0;
  double offset = 0.0;
};
StereoToneCurves align_stereo_tones(const GreyHistogram& left, const GreyHistogram& right, double saturation_excess,
                                    const LinearTone* measured = nullptr);

// The line that fits a tone curve best where the source image has pixels and the curve is off its
// ends (levels mapped inside [3, 250]), weighted by the source's pixel counts; the identity when
// fewer than two levels qualify. How the histograms see the cameras' relation, frame to frame.
LinearTone fit_linear_tone(const GreyLut& curve, const GreyHistogram& source);

}  // namespace heslam
