// The largest image heslam accepts from a file, a calibration or a message. A corrupt size field
// (a PNG header, a resolution typo, 0xFFFFFFFF in a message) must be refused with a line naming it,
// not passed to OpenCV, which would try to allocate gigabytes ("Failed to allocate 40000000000
// bytes") for pixels or rectification maps.
#pragma once

#include <cstdint>
#include <string>

namespace heslam {

// Above every camera heslam is for (EuRoC 752, KITTI 1241, 4K 3840, 8K 7680 px wide); the two
// rectification maps of an 8192x8192 camera take 512 MB, still allocatable.
constexpr std::uint64_t kMaxImageSidePx = 8192;

inline bool image_size_plausible(std::uint64_t width_px, std::uint64_t height_px) {
  return width_px > 0 && height_px > 0 && width_px <= kMaxImageSidePx && height_px <= kMaxImageSidePx;
}

// "WxH" for a message: what was expected when a size is not plausible.
inline std::string image_size_expectation() {
  return "expected 1.." + std::to_string(kMaxImageSidePx) + " px per side";
}

}  // namespace heslam
