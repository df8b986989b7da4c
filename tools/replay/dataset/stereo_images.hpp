// Loading one stereo pair's images exactly as they are stored (no conversion, no rectification).
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "tools/replay/dataset/stereo_dataset.hpp"

namespace heslam {

struct StereoImages {
  cv::Mat left;
  cv::Mat right;
  // "mono8" for one channel, "bgr8" for three (OpenCV's decode order), as StereoFrame.encoding.
  std::string encoding;
};

// Decodes both files with their stored depth and channels. Throws std::runtime_error with one line
// naming the file: missing, not decodable, not 8-bit, unsupported channel count, or left/right
// differing in size or channels.
StereoImages load_stereo_images(const StereoFrameFiles& frame);

}  // namespace heslam
