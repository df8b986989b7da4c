// The known image bytes of the security tests: a 16-byte marker repeated over a 752x480 image, so a
// capture of the loopback traffic can tell whether image payloads travel in the clear.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <span>
#include <string_view>
#include <vector>

namespace heslam::test {

inline constexpr std::string_view kPatternMarker = "HESLAM-PLAINTEXT";
inline constexpr uint32_t kPatternWidth = 752;  // an EuRoC image
inline constexpr uint32_t kPatternHeight = 480;

inline std::vector<uint8_t> pattern_image(std::size_t bytes) {
  std::vector<uint8_t> image(bytes);
  for (std::size_t i = 0; i < bytes; ++i) image[i] = static_cast<uint8_t>(kPatternMarker[i % kPatternMarker.size()]);
  return image;
}

// True when the marker occurs anywhere in bytes.
inline bool has_pattern(std::span<const uint8_t> bytes) {
  const auto* marker = reinterpret_cast<const uint8_t*>(kPatternMarker.data());
  return std::search(bytes.begin(), bytes.end(), marker, marker + kPatternMarker.size()) != bytes.end();
}

}  // namespace heslam::test
