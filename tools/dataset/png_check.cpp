// PNG chunk walk with CRC-32 (zlib's, the one PNG specifies), no decompression.
#include "tools/dataset/png_check.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>

#include <zlib.h>

#include "components/core/camera/image_limits.hpp"

namespace heslam {

namespace {

constexpr std::array<std::uint8_t, 8> kSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
constexpr std::size_t kChunkOverhead = 12;  // length, type, CRC
constexpr std::size_t kIhdrLength = 13;

std::uint32_t crc32_of(std::span<const std::uint8_t> bytes) {
  return static_cast<std::uint32_t>(::crc32(::crc32(0L, Z_NULL, 0), bytes.data(), static_cast<uInt>(bytes.size())));
}

std::uint32_t big_endian(std::span<const std::uint8_t> bytes, std::size_t at) {
  return (std::uint32_t{bytes[at]} << 24) | (std::uint32_t{bytes[at + 1]} << 16) | (std::uint32_t{bytes[at + 2]} << 8) |
         std::uint32_t{bytes[at + 3]};
}

std::string chunk_name(std::span<const std::uint8_t> bytes, std::size_t at) {
  std::string name;
  for (std::size_t i = 0; i < 4; ++i) {
    const char c = static_cast<char>(bytes[at + i]);
    name += (c >= 'A' && c <= 'z') ? c : '?';
  }
  return name;
}

}  // namespace

bool is_png(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= kSignature.size() && std::equal(kSignature.begin(), kSignature.end(), bytes.begin());
}

void check_png(std::span<const std::uint8_t> bytes) {
  const std::string file_size = std::to_string(bytes.size()) + " bytes";
  std::size_t at = kSignature.size();
  bool first = true;
  while (true) {
    if (at + kChunkOverhead > bytes.size()) {
      throw std::runtime_error("truncated PNG: the file ends after " + file_size + ", before its IEND chunk");
    }
    const std::uint32_t length = big_endian(bytes, at);
    const std::string name = chunk_name(bytes, at + 4);
    if (length > bytes.size() - at - kChunkOverhead) {
      throw std::runtime_error("truncated PNG: chunk " + name + " at byte " + std::to_string(at) + " needs " +
                               std::to_string(length + kChunkOverhead) + " bytes, the file ends after " + file_size);
    }
    const std::uint32_t stored_crc = big_endian(bytes, at + 8 + length);
    if (crc32_of(bytes.subspan(at + 4, 4 + length)) != stored_crc) {
      throw std::runtime_error("corrupt PNG: chunk " + name + " at byte " + std::to_string(at) +
                               " fails its CRC check");
    }
    if (first) {
      if (name != "IHDR" || length != kIhdrLength) {
        throw std::runtime_error("corrupt PNG: the first chunk is " + name + ", expected a 13-byte IHDR");
      }
      const std::uint32_t width = big_endian(bytes, at + 8);
      const std::uint32_t height = big_endian(bytes, at + 12);
      if (!image_size_plausible(width, height)) {
        throw std::runtime_error("PNG header says " + std::to_string(width) + "x" + std::to_string(height) +
                                 " pixels: " + image_size_expectation() + " (corrupt file?)");
      }
      first = false;
    }
    if (name == "IEND") return;
    at += kChunkOverhead + length;
  }
}

}  // namespace heslam
