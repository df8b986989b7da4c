// Loading one stereo pair's images exactly as they are stored (no conversion, no rectification).
#pragma once

#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "tools/dataset/stereo_dataset.hpp"

namespace heslam {

struct StereoImages {
  cv::Mat left;
  cv::Mat right;
  // "mono8" for one channel, "bgr8" for three (OpenCV's decode order), as StereoFrame.encoding.
  std::string encoding;
};

// One image file as stored (8-bit, 1 or 3 channels); throws one line naming the file.
cv::Mat load_image_file(const std::filesystem::path& path);

// Decodes both files with their stored depth and channels. Throws std::runtime_error with one line
// naming the file: missing, truncated or corrupt (PNG files are checked chunk by chunk first, see
// png_check.hpp), not 8-bit, unsupported channel count, another size than `calibrated_size` (the
// calibration's raw image size, when known), or left and right differing (both files named).
StereoImages load_stereo_images(const StereoFrameFiles& frame, std::optional<cv::Size> calibrated_size = std::nullopt);

}  // namespace heslam
