// Histogram equalization before ORB extraction (HE-SLAM's contribution), applied to a stereo pair
// so that stereo matching compares like with like. How the two images are related (HE.stereo):
// shared (one mapping from the joint histogram; right only if both cameras expose alike), matched
// (the right image's histogram is first matched to the left's -- a monotonic tone curve, which undoes
// a different gain, offset or gamma of the right camera -- then one mapping for both), separate (each
// image its own mapping).
//
// Modes: none; global (the paper: y = 255 * cdf(x)); clipped (global with the histogram clipped at
// a multiple of its mean bin, so a few dominant grey levels -- sky, a white wall, a dark floor -- do
// not stretch their neighbourhood into noise; the default, see docs/vision.md); clahe (contrast-limited, per tile,
// bilinear between tiles, tile LUTs from both images); adaptive (global HE only while the pair's contrast is low,
// switched with hysteresis so it does not flicker from frame to frame).
//
// Two forms, the same pixels: equalize() does the pair at once; the split form lets each image of
// the pair be measured and mapped on its own thread (the frontend's pair: each thread rectifies its
// image, takes its histogram, and after one barrier maps it and goes on to its ORB pyramid):
// add_histogram(left) || add_histogram(right), then compute_mappings() once, then apply(left) ||
// apply(right). equalize() is that same sequence on one thread.
#pragma once

#include <array>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/image/histogram_matching.hpp"

namespace heslam {

enum class HeMode { kNone, kGlobal, kClahe, kAdaptive, kClipped };

// How the mappings of the two images of a pair relate; see the header comment. Not used by mode none.
enum class StereoPhotometry { kShared, kMatched, kSeparate };

// "none" | "global" | "clipped" | "clahe" | "adaptive"; throws std::invalid_argument on anything else.
HeMode parse_he_mode(const std::string& name);
const char* to_string(HeMode mode);
// "shared" | "matched" | "separate"; throws std::invalid_argument on anything else.
StereoPhotometry parse_stereo_photometry(const std::string& name);
const char* to_string(StereoPhotometry stereo);

struct HistogramEqualizerOptions {
  HeMode mode = HeMode::kClipped;  // the paper's global HE, clipped (measured best on EuRoC, docs/vision.md)
  // Clipped: a bin of the pair's joint histogram is clipped at global_clip_limit x (mean bin count)
  // and the excess spread over all bins before the cdf mapping.
  double global_clip_limit = 2.0;
  // CLAHE: a histogram bin is clipped at clip_limit x (mean bin count), as cv::createCLAHE.
  double clahe_clip_limit = 2.0;
  int clahe_tiles_x = 8;
  int clahe_tiles_y = 8;
  // Adaptive: the contrast measure is the standard deviation of the grey levels of both images
  // (RMS contrast). Equalization switches on below `adaptive_on_below` and off above
  // `adaptive_off_above`. Well-exposed EuRoC MH01 frames measure 78-86; their x0.1 dark or x0.12
  // flat versions 8-10.
  double adaptive_on_below = 25.0;
  double adaptive_off_above = 35.0;
  StereoPhotometry stereo = StereoPhotometry::kMatched;  // measured best with cameras exposed apart (docs/vision.md)

  // Constants of the matched photometry below: measured once (docs/vision.md), not settings keys
  // (a settings file giving one is told it is not used); tests and benchmarks may set them.
  // Matched: a right camera that saturates more than this fraction of its pixels beyond the left's
  // own saturated fraction has the left clipped to its range (histogram_matching.hpp). Equally
  // exposed EuRoC MH01 pairs differ by up to 7.5 % (3-6 % saturated in each camera; a lamp one
  // camera sees and the other does not); right x1.5 saturates 17-35 % of the right image.
  double saturation_excess = 0.10;
  // Matched: how much of the right's tone curve is applied, by the mean grey-level shift it makes:
  // none below match_shift_from (a camera pair's own difference: EuRoC MH01's equally exposed pairs
  // measure 1-18.5 levels, and matching them moved the MH01 ATE by noise only, 3.8 -> 4.05 mm), all
  // from match_shift_full (right x1.5 against left x0.5 measures ~70), linear between.
  double match_shift_from = 20.0;
  double match_shift_full = 40.0;
  // Matched: a pair whose histograms' fitted gain (fit_linear_tone of the quantile curve) is beyond
  // this factor either way is exposed apart whatever its shift in grey levels: in dark images (EuRoC
  // x0.1) a left x0.5 / right x1.5 pair moves its pixels by only ~12 levels. Equally exposed MH01
  // pairs fit 0.89-1.04 (dark or not).
  double match_gain_from = 1.5;

  // Reads HE.mode, HE.stereo, HE.globalClipLimit, HE.clipLimit, HE.tilesX, HE.tilesY, HE.adaptiveOnBelow,
  // HE.adaptiveOffAbove.
  static HistogramEqualizerOptions from_yaml(const cv::FileNode& root, const std::string& source);
  bool operator==(const HistogramEqualizerOptions&) const = default;
};

class HistogramEqualizer {
 public:
  enum class Side { kLeft = 0, kRight = 1 };

  explicit HistogramEqualizer(const HistogramEqualizerOptions& options = {});

  // Inputs: 8-bit grey images (the pair). Outputs may alias the inputs. Not thread-safe (adaptive
  // mode keeps its on/off state between calls).
  void equalize(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out);

  // The split form of equalize(), per pair: add_histogram for both sides (the two calls may run at
  // once on two threads: each touches only its side's histograms), then compute_mappings() (one
  // thread, after both), then apply for both sides (again at once if wanted). `image` must be the
  // same in add_histogram and apply. Throws std::invalid_argument on an image that is not 8-bit grey
  // and non-empty, or (compute_mappings) on a pair of different sizes.
  void add_histogram(Side side, const cv::Mat& image);
  // `measured_tone` (matched only): the cameras' relation measured on image content (stereo_tone.hpp)
  // replaces the quantile curve between the two histograms; may be called again for the same pair.
  void compute_mappings(const LinearTone* measured_tone = nullptr);
  // Returns the equalized image: `image` itself when this side passes through unchanged (mode none,
  // adaptive while off with no tone curve), else `buffer`, (re)allocated to image's size and written
  // (buffer may be image: the mapping is per pixel).
  const cv::Mat& apply(Side side, const cv::Mat& image, cv::Mat& buffer) const;

  // Adaptive mode: whether the last pair was equalized. Other modes: whether they equalize at all.
  bool active() const { return active_; }
  // RMS contrast of the last pair (computed in every mode but none).
  double last_contrast() const { return last_contrast_; }
  // Matched: mean grey-level shift of the right image by its tone curve in the last pair (0 otherwise).
  double last_tone_shift() const { return last_tone_shift_; }
  // Matched: whether the last pair's cameras were exposed apart -- a shift of at least
  // match_shift_from, or a histogram gain beyond match_gain_from -- so that its tone curve applied.
  bool last_exposed_apart() const { return last_exposed_apart_; }
  // Matched: the line fitted to the last pair's quantile curve (fit_linear_tone), whatever curve was
  // applied: how the histograms see the cameras' relation, to follow its change frame to frame.
  const LinearTone& last_histogram_tone() const { return last_histogram_tone_; }

  const HistogramEqualizerOptions& options() const { return options_; }

 private:
  using Histogram = std::array<std::uint32_t, 256>;
  using Lut = std::array<std::uint8_t, 256>;

  // One image of the pair: what add_histogram measured and what compute_mappings made of it.
  struct SideState {
    cv::Size size;
    Histogram histogram{};         // the whole image (modes but none)
    std::vector<Histogram> tiles;  // CLAHE: per tile, row-major
    bool pass_through = true;      // apply returns the image itself
    // Global / clipped / adaptive: the whole mapping. CLAHE: the tone curve applied before the tile
    // mappings (the identity unless matched).
    Lut lut{};
    std::size_t tile_luts = 0;  // CLAHE: this side's tile mappings, an index into clahe_luts_
  };

  bool clahe() const { return options_.mode == HeMode::kClahe; }
  // CLAHE: the tile mappings of sides `images` (their tile histograms through their tone curves,
  // summed per tile, clipped).
  std::vector<Lut> clahe_tile_luts(std::initializer_list<const SideState*> images) const;
  // CLAHE: maps `in` through `tone`, then the bilinear blend of the four nearest tiles' mappings.
  void clahe_map(const cv::Mat& in, const Lut& tone, const std::vector<Lut>& luts, cv::Mat& out) const;

  HistogramEqualizerOptions options_;
  std::array<SideState, 2> sides_;
  std::array<std::vector<Lut>, 2> clahe_luts_;  // CLAHE: [0] shared (or the left's), [1] the right's when separate
  bool active_ = false;
  double last_contrast_ = 0.0;
  double last_tone_shift_ = 0.0;
  LinearTone last_histogram_tone_;
  bool last_exposed_apart_ = false;
};

}  // namespace heslam
