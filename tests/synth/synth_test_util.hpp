// Shared helpers of the heslam-synth tests: test presets and sub-pixel corner location.
#pragma once

#include <string>

#include <opencv2/imgproc.hpp>

#include "test_support.hpp"
#include "tools/synth/preset.hpp"

namespace heslam::synth::test {

inline Preset test_preset(const std::string& file_name) {
  return load_preset(::heslam::test::source_dir() / "tests" / "synth" / file_name);
}

inline Preset repo_preset(const std::string& name) { return load_preset(find_preset(name)); }

// Sub-pixel checkerboard corner near `guess` (OpenCV pixel convention).
inline cv::Point2f locate_corner(const cv::Mat& image, const cv::Point2f& guess) {
  std::vector<cv::Point2f> pts{guess};
  cv::cornerSubPix(image, pts, cv::Size(4, 4), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  return pts[0];
}

}  // namespace heslam::synth::test
