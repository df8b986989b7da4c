// A grey texture with a mip-map chain, sampled trilinearly so that minified textures do not alias.
//
// Texture space: s (columns) and t (rows) in texels of level 0, texel centres at i + 0.5; the
// texture repeats (wrap) in both directions. Sizes are powers of two so wrapping is a mask.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace heslam::synth {

class MipTexture {
 public:
  MipTexture() = default;
  // `image` is any 8-bit grey or colour image; it is converted to linear grey in [0, 1] and resized to
  // size_px x size_px (a power of two) before the chain is built.
  MipTexture(const cv::Mat& image, int size_px);

  int size_px() const { return levels_.empty() ? 0 : levels_.front().cols; }
  int num_levels() const { return static_cast<int>(levels_.size()); }
  const cv::Mat& level(int i) const { return levels_[static_cast<std::size_t>(i)]; }

  // Trilinear sample at (s, t) in level-0 texels, footprint_texels = size of one pixel in texels.
  float sample(float s, float t, float footprint_texels) const;

 private:
  float bilinear(int level, float s, float t) const;

  std::vector<cv::Mat> levels_;  // CV_32F, level i is size >> i
};

// Where the photographs come from (Debian package opencv-doc).
inline const std::filesystem::path kDefaultPhotoDir = "/usr/share/doc/opencv-doc/examples/data";

// Loads a photograph by file name from `photo_dir`; throws std::runtime_error naming the file and the
// package to install when it is missing.
MipTexture load_photo_texture(const std::filesystem::path& photo_dir, const std::string& file_name, int size_px);

// Procedural textures, deterministic for a seed.
enum class ProceduralKind { kConcrete, kTiles, kBricks, kAsphalt, kChecker, kPlaster };
MipTexture make_procedural_texture(ProceduralKind kind, std::uint64_t seed, int size_px);

// A checkerboard of `squares` x `squares` cells of cell_texels, surrounded by a white border of
// border_texels: the marker whose inner corners are exact known points for geometry tests.
struct CheckerLayout {
  int squares = 8;
  int cell_texels = 48;
  int border_texels = 64;
  int size_px() const { return squares * cell_texels + 2 * border_texels; }
};
MipTexture make_checker_marker(const CheckerLayout& layout);

// Inline: these run several times per rendered pixel.
namespace detail {
inline int fast_floor(float x) {
  const int i = static_cast<int>(x);
  return i > x ? i - 1 : i;
}
// log2 for x >= 1 from the float's exponent plus a quadratic in the mantissa (error < 0.01), enough
// to choose and blend mip levels.
inline float fast_log2(float x) {
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  const float exponent = static_cast<float>(static_cast<int>((bits >> 23) & 0xFF) - 127);
  bits = (bits & 0x007FFFFFu) | 0x3F800000u;  // mantissa in [1, 2)
  float m;
  std::memcpy(&m, &bits, sizeof(m));
  return exponent + (-0.34484843f * m + 2.02466578f) * m - 1.67487759f;
}
}  // namespace detail

inline float MipTexture::bilinear(int level, float s, float t) const {
  const cv::Mat& img = levels_[static_cast<std::size_t>(level)];
  const int mask = img.cols - 1;
  const float x = s - 0.5f;
  const float y = t - 0.5f;
  const int x0 = detail::fast_floor(x);
  const int y0 = detail::fast_floor(y);
  const float fx = x - static_cast<float>(x0);
  const float fy = y - static_cast<float>(y0);
  const float* row0 = img.ptr<float>(y0 & mask);
  const float* row1 = img.ptr<float>((y0 + 1) & mask);
  const int c0 = x0 & mask;
  const int c1 = (x0 + 1) & mask;
  const float top = row0[c0] + fx * (row0[c1] - row0[c0]);
  const float bottom = row1[c0] + fx * (row1[c1] - row1[c0]);
  return top + fy * (bottom - top);
}

inline float MipTexture::sample(float s, float t, float footprint_texels) const {
  const int last = num_levels() - 1;
  if (footprint_texels <= 1.0f) return bilinear(0, s, t);
  const float lod = std::min(detail::fast_log2(footprint_texels), static_cast<float>(last));
  const int l0 = std::min(static_cast<int>(lod), last);
  const float frac = lod - static_cast<float>(l0);
  const float scale0 = 1.0f / static_cast<float>(1 << l0);
  const float a = bilinear(l0, s * scale0, t * scale0);
  if (l0 == last || frac <= 0.0f) return a;
  const float b = bilinear(l0 + 1, s * scale0 * 0.5f, t * scale0 * 0.5f);
  return a + frac * (b - a);
}

}  // namespace heslam::synth
