// The photometric relation between the two cameras of a pair, left ~ gain x right + offset (raw
// grey levels), measured on the pair's own stereo matches and carried from frame to frame: what
// HE.stereo "matched" applies to the right image when the cameras are exposed apart.
//
// Why not from the two histograms alone (histogram_matching.hpp): the cameras see partly different
// scenes (the baseline, vignetting, what one of them clips), so the quantile curve between their
// histograms is a noisy estimate of the relation. On EuRoC MH01 with the left x4 and the right x1, the
// line fitted to it frame by frame has gains from 3.0 to 5.8; on the matches of a pair, 7 x 7 patches
// that show the same surface, the ratio of their standard deviations is the gain itself (docs/vision.md,
// "Cameras exposed apart"). Exposure time, analog gain and a different auto-exposure state are such a
// relation, also behind a gamma curve (a gain stays a gain).
//
// The matches come after the equalization that needs the relation, so a pair uses the median of the
// last pairs' measurements. Where that cannot hold -- an exposure step, seen as a jump of the
// histograms' own fit, or a measurement far from the recent ones -- the pair falls back to the
// quantile curve, and the measurements start again from the matches that curve gives (on a wrong
// curve the matches, and so the next measurement, would be wrong too: it must not feed itself).
// Deterministic for a given sequence of pairs.
#pragma once

#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/feature/features.hpp"
#include "components/core/image/histogram_matching.hpp"

namespace heslam {

struct StereoToneMeasureOptions {
  int half_window = 3;       // 7 x 7 pixels around the left keypoint and its right match (level 0)
  double min_texture = 2.0;  // std of the left patch in grey levels: flatter patches carry no gain
  int min_matches = 30;      // fewer usable matches: no measurement
};

struct StereoToneMeasurement {
  bool valid = false;  // at least min_matches usable matches
  LinearTone tone;     // medians over the matches
  int matches = 0;     // matches used
};

// Over the stereo matches of `features` whose two patches hold no pixel at 0 or 255 (clipped) and
// whose left patch has texture: gain = median of std(left) / std(right), offset = median of
// mean(left) - gain x mean(right). `left` and `right`: the rectified raw (not equalized) images the
// features were found on. Throws std::invalid_argument on images that are not 8-bit grey of one size.
StereoToneMeasurement measure_stereo_tone(const cv::Mat& left, const cv::Mat& right, const StereoFeatures& features,
                                          const StereoToneMeasureOptions& options = {});

// The recent measurements, carried to the next pairs.
struct StereoToneTrackerOptions {
  // The median of this many last measurements is the relation (one pair's measurement moves by a
  // few percent; the cameras' relation does not, between exposure changes).
  int window_pairs = 5;
  // A measurement older than this many pairs is not used.
  int max_age_pairs = 10;
  // The histograms' fitted gain changing by more than this factor from one pair to the next is an
  // exposure step: the measurements before it no longer hold. (The fit moves by up to ~8 % between
  // neighbouring pairs of one exposure.)
  double step_factor = 1.2;
  // A measurement off the recent ones' median by more than this factor is not trusted: the
  // measurements start again from a pair on the quantile curve.
  double jump_factor = 1.3;
};

class StereoToneTracker {
 public:
  explicit StereoToneTracker(const StereoToneTrackerOptions& options = {}) : options_(options) {}

  // The relation for a new pair whose histograms fit `histogram_tone` (HistogramEqualizer::
  // last_histogram_tone): the median of the recent measurements. Empty (use the quantile curve)
  // without a recent measurement or when the histograms show an exposure step.
  std::optional<LinearTone> predict(const LinearTone& histogram_tone) const;

  // After a pair exposed apart: its measurement (an invalid one only ages the others; one far off the
  // recent median drops them all) and its histograms' fit.
  void update(const StereoToneMeasurement& measurement, const LinearTone& histogram_tone);

  // Cameras exposed alike again: forget the measurements.
  void reset();

 private:
  // The histograms' gain changed by a step from the last pair's to `histogram_tone`.
  bool is_step(const LinearTone& histogram_tone) const;
  LinearTone recent_median() const;

  StereoToneTrackerOptions options_;
  std::vector<LinearTone> recent_;  // oldest first, at most window_pairs
  int age_pairs_ = 0;               // pairs since the newest of recent_
  bool have_last_histogram_ = false;
  LinearTone last_histogram_;  // the last pair's histograms' fit
};

}  // namespace heslam
