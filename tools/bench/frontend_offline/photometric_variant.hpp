// Photometric variants of real images for robustness runs: dark (x0.1 plus sensor noise) and low
// contrast (x0.12 around mid grey), generated deterministically per frame.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace heslam::bench {

enum class PhotometricVariant { kNone, kDark, kLowContrast };

// "none" | "dark" | "low_contrast"; throws std::runtime_error naming the value otherwise.
PhotometricVariant parse_photometric_variant(const std::string& name);
const char* to_string(PhotometricVariant variant);

// Applies the variant in place to an 8-bit grey image; `seed` makes the noise reproducible.
void apply_photometric_variant(cv::Mat& image, PhotometricVariant variant, std::uint64_t seed);

}  // namespace heslam::bench
