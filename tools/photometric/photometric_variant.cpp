// Dark and low-contrast image variants, and per-camera gains.
#include "tools/photometric/photometric_variant.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace heslam::photometric {
namespace {

constexpr double kDarkGain = 0.1;
constexpr double kDarkNoiseSigma = 1.0;  // grey levels: read noise that stays once the signal is tiny
constexpr double kLowContrastGain = 0.12;
constexpr double kMidGrey = 128.0;
// Added to the frame index to seed the right image's noise: independent of the left's, and of any
// other frame's for sequences below 2^32 frames.
constexpr std::uint64_t kRightImageSeedOffset = 0x100000000ULL;

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
    case PhotometricVariant::kNone: return;
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

std::string StereoGain::describe() const {
  if (equal_exposure()) return "1";
  char text[64];
  std::snprintf(text, sizeof text, "%g/%g", left, right);
  return text;
}

StereoGain parse_stereo_gain(const std::string& value) {
  const std::size_t comma = value.find(',');
  const auto fail = [&] {
    return std::runtime_error("--stereo-gain: expected L,R (two positive numbers), got '" + value + "'");
  };
  if (comma == std::string::npos) throw fail();
  StereoGain gain;
  const std::string left = value.substr(0, comma);
  const std::string right = value.substr(comma + 1);
  char* end = nullptr;
  gain.left = std::strtod(left.c_str(), &end);
  if (left.empty() || *end != '\0' || !(gain.left > 0.0)) throw fail();
  gain.right = std::strtod(right.c_str(), &end);
  if (right.empty() || *end != '\0' || !(gain.right > 0.0)) throw fail();
  return gain;
}

std::vector<StereoGain> parse_stereo_gain_schedule(const std::string& value) {
  std::vector<StereoGain> schedule;
  std::size_t begin = 0;
  while (begin <= value.size()) {
    const std::size_t slash = std::min(value.find('/', begin), value.size());
    schedule.push_back(parse_stereo_gain(value.substr(begin, slash - begin)));
    begin = slash + 1;
  }
  return schedule;
}

std::string describe(const std::vector<StereoGain>& schedule) {
  if (schedule.empty()) return "1";
  std::string text;
  for (const StereoGain& gain : schedule) text += (text.empty() ? "" : ", ") + gain.describe();
  return text;
}

StereoGain stereo_gain_at(const std::vector<StereoGain>& schedule, std::size_t index, std::size_t count) {
  if (schedule.empty() || count == 0) return {};
  return schedule[std::min(schedule.size() - 1, index * schedule.size() / count)];
}

void apply_gain(cv::Mat& image, double gain) {
  if (gain == 1.0) return;
  image.convertTo(image, CV_8U, gain);  // rounds and saturates to [0, 255]
}

void apply_to_pair(cv::Mat& left, cv::Mat& right, PhotometricVariant variant, const StereoGain& gain,
                   std::uint64_t frame_index) {
  apply_photometric_variant(left, variant, frame_index);
  apply_photometric_variant(right, variant, frame_index + kRightImageSeedOffset);
  apply_gain(left, gain.left);
  apply_gain(right, gain.right);
}

}  // namespace heslam::photometric
