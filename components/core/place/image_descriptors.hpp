// ORB descriptors of one grey image as the frontend computes them (histogram equalization, then
// ORB-SLAM2's ORB), for training vocabularies and scoring images without a stereo pipeline.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "components/core/feature/features.hpp"
#include "components/core/feature/orb_extractor.hpp"
#include "components/core/image/histogram_equalizer.hpp"

namespace heslam {

class ImageDescriptorExtractor {
 public:
  // Defaults are the frontend's: clipped HE, 1,200 features, 8 levels x 1.2.
  explicit ImageDescriptorExtractor(const HistogramEqualizerOptions& he = {}, const OrbOptions& orb = {});

  // Input: 8-bit grey or BGR image (converted to grey). Deterministic. Not thread-safe.
  std::vector<Descriptor> extract(const cv::Mat& image);

 private:
  HistogramEqualizer equalizer_;
  OrbExtractor extractor_;
  cv::Mat grey_, equalized_, unused_;
  OrbFeatures features_;
};

}  // namespace heslam
