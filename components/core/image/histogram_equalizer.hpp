// Histogram equalization before ORB extraction (HE-SLAM's contribution), applied to a stereo pair
// with ONE mapping for both images (from their joint histogram) so stereo SAD matching stays
// photometrically consistent.
//
// Modes: none; global (the paper: y = 255 * cdf(x)); clipped (global with the histogram clipped at
// a multiple of its mean bin, so a few dominant grey levels -- sky, a white wall, a dark floor -- do
// not stretch their neighbourhood into noise; the default, see docs/vision.md); clahe (contrast-limited, per tile, bilinear
// between tiles, tile LUTs from both images); adaptive (global HE only while the pair's contrast is
// low, switched with hysteresis so it does not flicker from frame to frame).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace heslam {

enum class HeMode { kNone, kGlobal, kClahe, kAdaptive, kClipped };

// "none" | "global" | "clipped" | "clahe" | "adaptive"; throws std::invalid_argument on anything else.
HeMode parse_he_mode(const std::string& name);
const char* to_string(HeMode mode);

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

  // Reads HE.mode, HE.globalClipLimit, HE.clipLimit, HE.tilesX, HE.tilesY, HE.adaptiveOnBelow, HE.adaptiveOffAbove.
  static HistogramEqualizerOptions from_yaml(const cv::FileNode& root, const std::string& source);
};

class HistogramEqualizer {
 public:
  explicit HistogramEqualizer(const HistogramEqualizerOptions& options = {});

  // Inputs: 8-bit grey images (the pair). Outputs may alias the inputs. Not thread-safe (adaptive
  // mode keeps its on/off state between calls).
  void equalize(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out);

  // Adaptive mode: whether the last pair was equalized. Other modes: whether they equalize at all.
  bool active() const { return active_; }
  // RMS contrast of the last pair (computed in every mode but none).
  double last_contrast() const { return last_contrast_; }

  const HistogramEqualizerOptions& options() const { return options_; }

 private:
  void equalize_global(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out,
                       const std::array<std::uint32_t, 256>& histogram) const;
  // Returns the pair's RMS contrast.
  double equalize_clahe(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out) const;

  HistogramEqualizerOptions options_;
  bool active_ = false;
  double last_contrast_ = 0.0;
};

}  // namespace heslam
