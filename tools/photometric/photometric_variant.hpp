// Photometric variants of real images for robustness runs: dark (x0.1 plus sensor noise) and low
// contrast (x0.12 around mid grey), generated deterministically per frame; and a stereo gain, a
// different exposure of the left and right camera (x gain, clipped to 8 bit), as auto-exposure run
// per camera or a flared / shaded lens gives. Shared by heslam-frontend-offline (in memory) and
// heslam-photometric (a transformed copy of a dataset folder), so both see the same images.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace heslam::photometric {

enum class PhotometricVariant { kNone, kDark, kLowContrast };

// "none" | "dark" | "low_contrast"; throws std::runtime_error naming the value otherwise.
PhotometricVariant parse_photometric_variant(const std::string& name);
const char* to_string(PhotometricVariant variant);

// Applies the variant in place to an 8-bit grey image; `seed` makes the noise reproducible.
void apply_photometric_variant(cv::Mat& image, PhotometricVariant variant, std::uint64_t seed);

// Per-camera exposure gains, applied after the variant: grey x gain, rounded and saturated to
// [0, 255] (a gain > 1 clips the bright parts of that image, as an over-exposed camera does).
struct StereoGain {
  double left = 1.0;
  double right = 1.0;

  bool equal_exposure() const { return left == 1.0 && right == 1.0; }
  std::string describe() const;  // "1" or "0.5/1.5"
};

// "L,R" (e.g. "0.5,1.5"), both positive; throws std::runtime_error naming the value otherwise.
StereoGain parse_stereo_gain(const std::string& value);

// "L,R" or several "L,R/L,R/...": a schedule whose entries split a run into equal consecutive
// blocks of frames (exposures that change during the run, as auto-exposure steps do).
std::vector<StereoGain> parse_stereo_gain_schedule(const std::string& value);
std::string describe(const std::vector<StereoGain>& schedule);  // "1" or "0.5/1.5, 1/4"

// The schedule's entry for frame `index` of a run of `count` frames (equal blocks; none: gain 1).
StereoGain stereo_gain_at(const std::vector<StereoGain>& schedule, std::size_t index, std::size_t count);

// image = saturate(image x gain); no-op for gain 1.
void apply_gain(cv::Mat& image, double gain);

// The whole transform of stereo pair `frame_index` (its 0-based index in the sequence, which seeds
// the variant's noise; the right image's noise is seeded apart from the left's): the variant on both
// images, then `gain`.
void apply_to_pair(cv::Mat& left, cv::Mat& right, PhotometricVariant variant, const StereoGain& gain,
                   std::uint64_t frame_index);

}  // namespace heslam::photometric
