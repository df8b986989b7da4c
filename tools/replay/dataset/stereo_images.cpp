// Decodes a stereo pair's files as stored, and says which file is wrong when one is.
#include "tools/replay/dataset/stereo_images.hpp"

#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace heslam {

namespace {

cv::Mat load_image(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path.string() + ": image file missing");
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw std::runtime_error(path.string() + ": cannot be decoded as an image (corrupt file?)");
  if (image.depth() != CV_8U) {
    throw std::runtime_error(path.string() + ": " + std::to_string(8 * image.elemSize1()) +
                             "-bit image; expected 8-bit grey or colour");
  }
  if (image.channels() != 1 && image.channels() != 3) {
    throw std::runtime_error(path.string() + ": " + std::to_string(image.channels()) +
                             " channels; expected 1 (grey) or 3 (colour)");
  }
  return image;
}

}  // namespace

StereoImages load_stereo_images(const StereoFrameFiles& frame) {
  StereoImages images;
  images.left = load_image(frame.left);
  images.right = load_image(frame.right);
  if (images.left.size() != images.right.size() || images.left.type() != images.right.type()) {
    throw std::runtime_error(frame.right.string() + ": " + std::to_string(images.right.cols) + "x" +
                             std::to_string(images.right.rows) + "x" + std::to_string(images.right.channels()) +
                             " differs from the left image " + std::to_string(images.left.cols) + "x" +
                             std::to_string(images.left.rows) + "x" + std::to_string(images.left.channels()));
  }
  images.encoding = images.left.channels() == 1 ? "mono8" : "bgr8";
  return images;
}

}  // namespace heslam
