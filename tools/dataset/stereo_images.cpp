// Decodes a stereo pair's files as stored, and says which file is wrong when one is.
#include "tools/dataset/stereo_images.hpp"

#include <fstream>
#include <iterator>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "tools/dataset/png_check.hpp"

namespace heslam {

namespace {

std::string size_text(const cv::Mat& image) {
  return std::to_string(image.cols) + "x" + std::to_string(image.rows) + "x" + std::to_string(image.channels());
}

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw std::runtime_error(path.string() + ": image file missing");
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  std::ifstream in(path, std::ios::binary);
  if (!in || error) throw std::runtime_error(path.string() + ": cannot open the image file");
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (in.gcount() != static_cast<std::streamsize>(bytes.size())) {
    throw std::runtime_error(path.string() + ": read error (got " + std::to_string(in.gcount()) + " of " +
                             std::to_string(size) + " bytes)");
  }
  return bytes;
}

}  // namespace

cv::Mat load_image_file(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  // PNG (every EuRoC and KITTI image) is checked first: libpng would report a damaged file only with
  // an anonymous "libpng error" line on stderr.
  if (is_png(bytes)) {
    try {
      check_png(bytes);
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(path.string() + ": " + error.what());
    }
  }
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& error) {
    throw std::runtime_error(path.string() + ": cannot be decoded as an image (OpenCV: " + error.err + ")");
  }
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

StereoImages load_stereo_images(const StereoFrameFiles& frame, std::optional<cv::Size> calibrated_size) {
  StereoImages images;
  images.left = load_image_file(frame.left);
  images.right = load_image_file(frame.right);
  if (calibrated_size) {
    // The calibration says which size is right, so the file at fault can be named.
    for (const auto& [image, path] : {std::pair{&images.left, &frame.left}, std::pair{&images.right, &frame.right}}) {
      if (image->size() != *calibrated_size) {
        throw std::runtime_error(path->string() + ": " + std::to_string(image->cols) + "x" +
                                 std::to_string(image->rows) + " image; the calibration says " +
                                 std::to_string(calibrated_size->width) + "x" +
                                 std::to_string(calibrated_size->height));
      }
    }
  }
  if (images.left.size() != images.right.size() || images.left.type() != images.right.type()) {
    // Without a calibration to compare with, neither side can be blamed: name both.
    throw std::runtime_error("stereo pair differs in size or channels: " + frame.left.string() + " is " +
                             size_text(images.left) + ", " + frame.right.string() + " is " + size_text(images.right));
  }
  images.encoding = images.left.channels() == 1 ? "mono8" : "bgr8";
  return images;
}

}  // namespace heslam
