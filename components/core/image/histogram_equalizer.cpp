// Equalization of a stereo pair: global (paper), clipped, CLAHE, adaptive; shared, matched or separate
// mappings for the two images.
#include "components/core/image/histogram_equalizer.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <vector>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "components/core/image/histogram_matching.hpp"
#include "components/core/image/yaml_option.hpp"

namespace heslam {
namespace {

constexpr int kLevels = 256;  // 8-bit grey

using Histogram = GreyHistogram;
using Lut = GreyLut;

// Adds the histogram of `image` (region `roi`) to `histogram`. Four partial histograms break the
// store-to-load dependency of runs of equal pixels, about 2x faster than one.
void accumulate_histogram(const cv::Mat& image, const cv::Rect& roi, Histogram& histogram) {
  std::array<std::array<std::uint32_t, kLevels>, 4> partial{};
  for (int y = roi.y; y < roi.y + roi.height; ++y) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y) + roi.x;
    int x = 0;
    for (; x + 4 <= roi.width; x += 4) {
      ++partial[0][row[x]];
      ++partial[1][row[x + 1]];
      ++partial[2][row[x + 2]];
      ++partial[3][row[x + 3]];
    }
    for (; x < roi.width; ++x) ++partial[0][row[x]];
  }
  for (int v = 0; v < kLevels; ++v) histogram[v] += partial[0][v] + partial[1][v] + partial[2][v] + partial[3][v];
}

// The paper's mapping y = 255 * cdf(x), cdf normalized to [0, 1].
Lut cdf_lut(const Histogram& histogram) {
  std::uint64_t total = 0;
  for (std::uint32_t h : histogram) total += h;
  Lut lut{};
  if (total == 0) return lut;
  std::uint64_t cumulative = 0;
  for (int v = 0; v < kLevels; ++v) {
    cumulative += histogram[v];
    lut[v] = static_cast<std::uint8_t>((255 * cumulative + total / 2) / total);
  }
  return lut;
}

// Clips every bin at clip_limit x the mean bin count and spreads the excess evenly over all bins,
// as cv::CLAHE does per tile. `count` is the number of pixels in the histogram.
void clip_histogram(Histogram& histogram, double clip_limit, std::uint64_t count) {
  const auto clip = std::max<std::uint32_t>(1u, static_cast<std::uint32_t>(clip_limit * count / kLevels));
  std::uint32_t excess = 0;
  for (std::uint32_t& bin : histogram) {
    if (bin > clip) {
      excess += bin - clip;
      bin = clip;
    }
  }
  const std::uint32_t batch = excess / kLevels;
  const std::uint32_t residual = excess - batch * kLevels;
  for (std::uint32_t& bin : histogram) bin += batch;
  if (residual > 0) {
    const std::uint32_t step = std::max<std::uint32_t>(kLevels / residual, 1u);
    for (std::uint32_t v = 0, given = 0; v < static_cast<std::uint32_t>(kLevels) && given < residual;
         v += step, ++given) {
      ++histogram[v];
    }
  }
}

// The histogram of `image` after mapping it through `lut`, from its histogram (no pass over pixels).
Histogram mapped_histogram(const Histogram& histogram, const Lut& lut) {
  Histogram out{};
  for (int v = 0; v < kLevels; ++v) out[lut[v]] += histogram[v];
  return out;
}

// first[second[v]]: two LUTs as one, so the right image is mapped in one pass.
Lut compose(const Lut& first, const Lut& second) {
  Lut out{};
  for (int v = 0; v < kLevels; ++v) out[v] = first[second[v]];
  return out;
}

// lut[src[x]] for x < n. With AVX2, 32 pixels at a time: the LUT as 16 tables of 16 entries, each
// looked up by the low nibble (pshufb), the high nibble choosing among the 16 results in a tree of
// byte blends (its bit 4 between pairs, bit 5 between those, ...): about 1.2 instructions per pixel
// instead of 6 (callgrind; the scalar loop's loads and stores).
void lut_row(const std::uint8_t* src, std::uint8_t* dst, std::size_t n, const Lut& lut) {
  std::size_t x = 0;
#if defined(__AVX2__)
  __m256i tables[16];
  for (int i = 0; i < 16; ++i) {
    tables[i] = _mm256_broadcastsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(lut.data() + 16 * i)));
  }
  const __m256i low_nibble = _mm256_set1_epi8(0x0F);
  for (; x + 32 <= n; x += 32) {
    const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(src + x));
    const __m256i index = _mm256_and_si256(v, low_nibble);  // bit 7 clear: pshufb looks up, never zeroes
    __m256i level[16];
    for (int i = 0; i < 16; ++i) level[i] = _mm256_shuffle_epi8(tables[i], index);
    // blendv takes each byte's top bit: bit 4 + k of the pixel moved there by a 16-bit shift (the
    // bits shifted in from the neighbouring byte stay below the top bit).
    for (int bit = 0, count = 16; bit < 4; ++bit, count /= 2) {
      const __m256i select = _mm256_slli_epi16(v, 3 - bit);
      for (int i = 0; i < count / 2; ++i) {
        level[i] = _mm256_blendv_epi8(level[2 * i], level[2 * i + 1], select);
      }
    }
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst + x), level[0]);
  }
#endif
  for (; x < n; ++x) dst[x] = lut[src[x]];
}

// out = lut[in] on the calling thread (cv::LUT hands an image this large to OpenCV's pool, a third
// thread on the frontend's two cores). `out` may be `in`.
void apply_lut(const cv::Mat& in, cv::Mat& out, const Lut& lut) {
  out.create(in.size(), CV_8UC1);
  if (in.isContinuous() && out.isContinuous()) {
    lut_row(in.ptr<std::uint8_t>(0), out.ptr<std::uint8_t>(0), in.total(), lut);
    return;
  }
  for (int y = 0; y < in.rows; ++y) {
    lut_row(in.ptr<std::uint8_t>(y), out.ptr<std::uint8_t>(y), static_cast<std::size_t>(in.cols), lut);
  }
}

double rms_contrast(const Histogram& histogram) {
  double n = 0.0;
  double sum = 0.0;
  double sum2 = 0.0;
  for (int v = 0; v < kLevels; ++v) {
    n += histogram[v];
    sum += static_cast<double>(v) * histogram[v];
    sum2 += static_cast<double>(v) * v * histogram[v];
  }
  if (n == 0.0) return 0.0;
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

void check_image(const cv::Mat& image) {
  if (image.type() != CV_8UC1 || image.empty()) {
    throw std::invalid_argument("HistogramEqualizer: expected a non-empty 8-bit grey image");
  }
}

// CLAHE's tiles over an image: tiles_x x tiles_y rectangles of tile_w x tile_h, the last ones cut
// at the image's edge (some may be empty when the image is narrower than the grid).
struct TileGrid {
  TileGrid(const HistogramEqualizerOptions& options, cv::Size size)
      : tiles_x(options.clahe_tiles_x),
        tiles_y(options.clahe_tiles_y),
        tile_w((size.width + tiles_x - 1) / tiles_x),
        tile_h((size.height + tiles_y - 1) / tiles_y),
        image(0, 0, size.width, size.height) {}
  cv::Rect roi(int tx, int ty) const { return cv::Rect(tx * tile_w, ty * tile_h, tile_w, tile_h) & image; }

  int tiles_x;
  int tiles_y;
  int tile_w;
  int tile_h;
  cv::Rect image;
};

void check_pair(const cv::Mat& left, const cv::Mat& right) {
  if (left.type() != CV_8UC1 || right.type() != CV_8UC1 || left.size() != right.size() || left.empty()) {
    throw std::invalid_argument("HistogramEqualizer: expected two non-empty 8-bit grey images of the same size");
  }
}

}  // namespace

HeMode parse_he_mode(const std::string& name) {
  if (name == "none") return HeMode::kNone;
  if (name == "global") return HeMode::kGlobal;
  if (name == "clahe") return HeMode::kClahe;
  if (name == "adaptive") return HeMode::kAdaptive;
  if (name == "clipped") return HeMode::kClipped;
  throw std::invalid_argument("HE mode '" + name + "': expected none | global | clipped | clahe | adaptive");
}

StereoPhotometry parse_stereo_photometry(const std::string& name) {
  if (name == "shared") return StereoPhotometry::kShared;
  if (name == "matched") return StereoPhotometry::kMatched;
  if (name == "separate") return StereoPhotometry::kSeparate;
  throw std::invalid_argument("HE stereo '" + name + "': expected shared | matched | separate");
}

const char* to_string(StereoPhotometry stereo) {
  switch (stereo) {
    case StereoPhotometry::kShared: return "shared";
    case StereoPhotometry::kMatched: return "matched";
    case StereoPhotometry::kSeparate: return "separate";
  }
  return "unknown";
}

const char* to_string(HeMode mode) {
  switch (mode) {
    case HeMode::kNone: return "none";
    case HeMode::kGlobal: return "global";
    case HeMode::kClahe: return "clahe";
    case HeMode::kAdaptive: return "adaptive";
    case HeMode::kClipped: return "clipped";
  }
  return "unknown";
}

HistogramEqualizerOptions HistogramEqualizerOptions::from_yaml(const cv::FileNode& root, const std::string& source) {
  HistogramEqualizerOptions o;
  std::string mode = to_string(o.mode);
  yaml_option::read(root, "HE.mode", source, mode);
  try {
    o.mode = parse_he_mode(mode);
  } catch (const std::invalid_argument&) {
    yaml_option::fail(source, "HE.mode", "none | global | clipped | clahe | adaptive, got '" + mode + "'");
  }
  std::string stereo = to_string(o.stereo);
  yaml_option::read(root, "HE.stereo", source, stereo);
  try {
    o.stereo = parse_stereo_photometry(stereo);
  } catch (const std::invalid_argument&) {
    yaml_option::fail(source, "HE.stereo", "shared | matched | separate, got '" + stereo + "'");
  }
  yaml_option::read(root, "HE.clipLimit", source, o.clahe_clip_limit);
  yaml_option::read(root, "HE.globalClipLimit", source, o.global_clip_limit);
  yaml_option::read(root, "HE.tilesX", source, o.clahe_tiles_x);
  yaml_option::read(root, "HE.tilesY", source, o.clahe_tiles_y);
  yaml_option::read(root, "HE.adaptiveOnBelow", source, o.adaptive_on_below);
  yaml_option::read(root, "HE.adaptiveOffAbove", source, o.adaptive_off_above);
  if (!(o.clahe_clip_limit > 0.0) || o.clahe_clip_limit > 1000.0)
    yaml_option::fail(source, "HE.clipLimit", "a number in (0, 1000]");
  if (!(o.global_clip_limit > 0.0) || o.global_clip_limit > 1000.0) {
    yaml_option::fail(source, "HE.globalClipLimit", "a number in (0, 1000]");
  }
  if (o.clahe_tiles_x < 1 || o.clahe_tiles_x > 64) yaml_option::fail(source, "HE.tilesX", "an integer in [1, 64]");
  if (o.clahe_tiles_y < 1 || o.clahe_tiles_y > 64) yaml_option::fail(source, "HE.tilesY", "an integer in [1, 64]");
  if (!(o.adaptive_on_below >= 0.0) || o.adaptive_on_below > 255.0) {
    yaml_option::fail(source, "HE.adaptiveOnBelow", "a grey-level contrast in [0, 255]");
  }
  if (!(o.adaptive_off_above >= 0.0) || o.adaptive_off_above > 255.0) {
    yaml_option::fail(source, "HE.adaptiveOffAbove", "a grey-level contrast in [0, 255]");
  }
  if (o.adaptive_off_above < o.adaptive_on_below) {
    yaml_option::fail(source, "HE.adaptiveOffAbove", "a value >= HE.adaptiveOnBelow (hysteresis)");
  }
  return o;
}

HistogramEqualizer::HistogramEqualizer(const HistogramEqualizerOptions& options)
    : options_(options), active_(options.mode != HeMode::kNone && options.mode != HeMode::kAdaptive) {}

void HistogramEqualizer::equalize(const cv::Mat& left, const cv::Mat& right, cv::Mat& left_out, cv::Mat& right_out) {
  check_pair(left, right);
  add_histogram(Side::kLeft, left);
  add_histogram(Side::kRight, right);
  compute_mappings();
  if (const cv::Mat& out = apply(Side::kLeft, left, left_out); &out != &left_out) left_out = left;
  if (const cv::Mat& out = apply(Side::kRight, right, right_out); &out != &right_out) right_out = right;
}

void HistogramEqualizer::add_histogram(Side side, const cv::Mat& image) {
  check_image(image);
  SideState& state = sides_[static_cast<std::size_t>(side)];
  state.size = image.size();
  if (options_.mode == HeMode::kNone) return;
  state.histogram = {};
  if (!clahe()) {
    accumulate_histogram(image, cv::Rect(0, 0, image.cols, image.rows), state.histogram);
    return;
  }
  // CLAHE: per tile; the whole image's histogram is their sum (the tiles cover it exactly once).
  const TileGrid grid(options_, image.size());
  state.tiles.assign(static_cast<std::size_t>(grid.tiles_x * grid.tiles_y), Histogram{});
  for (int ty = 0; ty < grid.tiles_y; ++ty) {
    for (int tx = 0; tx < grid.tiles_x; ++tx) {
      const cv::Rect roi = grid.roi(tx, ty);
      Histogram& h = state.tiles[static_cast<std::size_t>(ty * grid.tiles_x + tx)];
      if (roi.area() > 0) accumulate_histogram(image, roi, h);
      for (int v = 0; v < kLevels; ++v) state.histogram[v] += h[v];
    }
  }
}

void HistogramEqualizer::compute_mappings(const LinearTone* measured_tone) {
  SideState& left = sides_[0];
  SideState& right = sides_[1];
  if (left.size != right.size || left.size.empty()) {
    throw std::invalid_argument("HistogramEqualizer: expected the histograms of two images of the same size");
  }
  for (SideState* state : {&left, &right}) {
    state->pass_through = true;
    state->tile_luts = 0;
    for (int v = 0; v < kLevels; ++v) state->lut[v] = static_cast<std::uint8_t>(v);
  }
  if (options_.mode == HeMode::kNone) return;

  Histogram left_histogram = left.histogram;
  Histogram right_histogram = right.histogram;
  // Matched: the tone curves first (composed with the HE mapping below, so each image is still
  // mapped in one pass); the mapped histograms follow from the LUTs.
  Lut left_tone{};
  Lut right_tone{};
  for (int v = 0; v < kLevels; ++v) left_tone[v] = right_tone[v] = static_cast<std::uint8_t>(v);
  last_tone_shift_ = 0.0;
  last_exposed_apart_ = false;
  if (options_.stereo == StereoPhotometry::kMatched) {
    const StereoToneCurves curves =
        align_stereo_tones(left_histogram, right_histogram, options_.saturation_excess, measured_tone);
    last_histogram_tone_ = fit_linear_tone(curves.quantile, right_histogram);
    last_tone_shift_ = curves.mean_right_shift;
    const double gain = last_histogram_tone_.gain;
    const bool gain_apart = gain > options_.match_gain_from || gain * options_.match_gain_from < 1.0;
    last_exposed_apart_ = curves.mean_right_shift >= options_.match_shift_from || gain_apart;
    left_tone = curves.left;
    right_tone = curves.right;
    if (!curves.left_clipped) {
      // The pair's own difference (EuRoC MH01's cameras: up to 18 grey levels) keeps the shared
      // mapping; the curve fades in linearly up to match_shift_full, so no frame-to-frame switch.
      // A gain beyond match_gain_from applies it whole (dark images shift by few grey levels).
      const double weight = gain_apart ? 1.0
                                       : std::clamp((curves.mean_right_shift - options_.match_shift_from) /
                                                        (options_.match_shift_full - options_.match_shift_from),
                                                    0.0, 1.0);
      for (int v = 0; v < kLevels; ++v) {
        right_tone[v] = static_cast<std::uint8_t>(std::lround(v + weight * (curves.right[v] - v)));
      }
    }
    left_histogram = mapped_histogram(left_histogram, left_tone);
    right_histogram = mapped_histogram(right_histogram, right_tone);
  }
  Histogram joint = left_histogram;
  for (int v = 0; v < kLevels; ++v) joint[v] += right_histogram[v];
  last_contrast_ = rms_contrast(joint);

  if (clahe()) {  // tile LUTs of both images (matched: after their tone curves), or of each when separate
    left.lut = left_tone;
    right.lut = right_tone;
    left.pass_through = right.pass_through = false;
    if (options_.stereo == StereoPhotometry::kSeparate) {
      clahe_luts_[0] = clahe_tile_luts({&left});
      clahe_luts_[1] = clahe_tile_luts({&right});
      left.tile_luts = 0;
      right.tile_luts = 1;
    } else {
      clahe_luts_[0] = clahe_tile_luts({&left, &right});
      left.tile_luts = right.tile_luts = 0;
    }
    return;
  }

  if (options_.mode == HeMode::kAdaptive) {
    if (active_ && last_contrast_ > options_.adaptive_off_above) active_ = false;
    if (!active_ && last_contrast_ < options_.adaptive_on_below) active_ = true;
    if (!active_) {
      if (options_.stereo == StereoPhotometry::kMatched) {
        left.lut = left_tone;
        right.lut = right_tone;
        left.pass_through = right.pass_through = false;
      }
      return;
    }
  }

  // Global / clipped / adaptive (on): y = 255 cdf(x) of the (clipped) histogram.
  auto he_lut = [&](Histogram histogram, std::uint64_t pixels) {
    if (options_.mode == HeMode::kClipped) clip_histogram(histogram, options_.global_clip_limit, pixels);
    return cdf_lut(histogram);
  };
  const auto left_pixels = static_cast<std::uint64_t>(left.size.area());
  const auto right_pixels = static_cast<std::uint64_t>(right.size.area());
  left.pass_through = right.pass_through = false;
  if (options_.stereo == StereoPhotometry::kSeparate) {
    left.lut = he_lut(left_histogram, left_pixels);
    right.lut = he_lut(right_histogram, right_pixels);
    return;
  }
  const Lut lut = he_lut(joint, left_pixels + right_pixels);
  left.lut = compose(lut, left_tone);
  right.lut = compose(lut, right_tone);
}

const cv::Mat& HistogramEqualizer::apply(Side side, const cv::Mat& image, cv::Mat& buffer) const {
  const SideState& state = sides_[static_cast<std::size_t>(side)];
  if (image.type() != CV_8UC1 || image.size() != state.size) {
    throw std::invalid_argument("HistogramEqualizer::apply: expected the 8-bit grey image add_histogram measured");
  }
  if (state.pass_through) return image;
  if (clahe()) {
    clahe_map(image, state.lut, clahe_luts_[state.tile_luts], buffer);
  } else {
    apply_lut(image, buffer, state.lut);
  }
  return buffer;
}

std::vector<HistogramEqualizer::Lut> HistogramEqualizer::clahe_tile_luts(
    std::initializer_list<const SideState*> images) const {
  // One clipped-histogram LUT per tile, from the same tile of the given images.
  const TileGrid grid(options_, sides_[0].size);
  std::vector<Lut> luts(static_cast<std::size_t>(grid.tiles_x * grid.tiles_y));
  for (int ty = 0; ty < grid.tiles_y; ++ty) {
    for (int tx = 0; tx < grid.tiles_x; ++tx) {
      const auto tile = static_cast<std::size_t>(ty * grid.tiles_x + tx);
      Histogram h{};
      for (const SideState* image : images) {
        const Histogram mapped = mapped_histogram(image->tiles[tile], image->lut);
        for (int v = 0; v < kLevels; ++v) h[v] += mapped[v];
      }
      const int area = std::max(grid.roi(tx, ty).area(), 0);
      clip_histogram(h, options_.clahe_clip_limit, images.size() * static_cast<std::uint64_t>(area));
      luts[tile] = cdf_lut(h);
    }
  }
  return luts;
}

void HistogramEqualizer::clahe_map(const cv::Mat& in, const Lut& tone, const std::vector<Lut>& luts,
                                   cv::Mat& out) const {
  // Bilinear interpolation between the LUTs of the four nearest tile centres.
  const TileGrid grid(options_, in.size());
  const int tiles_x = grid.tiles_x;
  const int tiles_y = grid.tiles_y;
  const int width = in.cols;
  std::vector<int> x0(static_cast<std::size_t>(width)), x1(static_cast<std::size_t>(width));
  std::vector<float> wx(static_cast<std::size_t>(width));
  for (int x = 0; x < width; ++x) {
    const float t = (static_cast<float>(x) + 0.5f) / static_cast<float>(grid.tile_w) - 0.5f;
    const int i = static_cast<int>(std::floor(t));
    wx[x] = t - static_cast<float>(i);
    x0[x] = std::clamp(i, 0, tiles_x - 1);
    x1[x] = std::clamp(i + 1, 0, tiles_x - 1);
  }
  out.create(in.size(), CV_8UC1);  // per pixel, so `out` may be `in`
  for (int y = 0; y < in.rows; ++y) {
    const float t = (static_cast<float>(y) + 0.5f) / static_cast<float>(grid.tile_h) - 0.5f;
    const int j = static_cast<int>(std::floor(t));
    const float wy = t - static_cast<float>(j);
    const Lut* row0 = &luts[static_cast<std::size_t>(std::clamp(j, 0, tiles_y - 1) * tiles_x)];
    const Lut* row1 = &luts[static_cast<std::size_t>(std::clamp(j + 1, 0, tiles_y - 1) * tiles_x)];
    const std::uint8_t* src = in.ptr<std::uint8_t>(y);
    std::uint8_t* dst = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < width; ++x) {
      const std::uint8_t v = tone[src[x]];
      const float top = row0[x0[x]][v] + wx[x] * (static_cast<float>(row0[x1[x]][v]) - row0[x0[x]][v]);
      const float bottom = row1[x0[x]][v] + wx[x] * (static_cast<float>(row1[x1[x]][v]) - row1[x0[x]][v]);
      dst[x] = static_cast<std::uint8_t>(std::lround(top + wy * (bottom - top)));
    }
  }
}

}  // namespace heslam
