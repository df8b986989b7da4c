// Dark and low-contrast image variants.
#include "tools/bench/frontend_offline/photometric_variant.hpp"

#include <stdexcept>

namespace heslam::bench {
namespace {

constexpr double kDarkGain = 0.1;
constexpr double kDarkNoiseSigma = 1.0;  // grey levels: read noise that stays once the signal is tiny
constexpr double kLowContrastGain = 0.12;
constexpr double kMidGrey = 128.0;

}  // namespace

PhotometricVariant parse_photometric_variant(const std::string& name) {
  if (name == "none") return PhotometricVariant::kNone;
  if (name == "dark") return PhotometricVariant::kDark;
  if (name == "low_contrast") return PhotometricVariant::kLowContrast;
  throw std::runtime_error("--variant: expected none, dark or low_contrast, got '" + name + "'");
}

const char* to_string(PhotometricVariant variant) {
  switch (variant) {
    case PhotometricVariant::kNone: return "none";
    case PhotometricVariant::kDark: return "dark";
    case PhotometricVariant::kLowContrast: return "low_contrast";
  }
  return "unknown";
}

void apply_photometric_variant(cv::Mat& image, PhotometricVariant variant, std::uint64_t seed) {
  switch (variant) {
    case PhotometricVariant::kNone:
      return;
    case PhotometricVariant::kDark: {
      cv::Mat scaled;
      image.convertTo(scaled, CV_32F, kDarkGain);
      cv::Mat noise(image.size(), CV_32F);
      cv::RNG rng(seed);
      rng.fill(noise, cv::RNG::NORMAL, 0.0, kDarkNoiseSigma);
      scaled += noise;
      scaled.convertTo(image, CV_8U);  // rounds and saturates to [0, 255]
      return;
    }
    case PhotometricVariant::kLowContrast:
      image.convertTo(image, CV_8U, kLowContrastGain, kMidGrey * (1.0 - kLowContrastGain));
      return;
  }
}

}  // namespace heslam::bench
