// ORB-SLAM2-style stereo matching: descriptor match in the row band, SAD subpixel refinement, outliers.
#include "components/core/match/stereo_matcher.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>

#include "components/core/image/yaml_option.hpp"

#if defined(__SSE4_1__)
#include <smmintrin.h>
#endif

namespace heslam {
namespace {

// Fixed-point scale of the relative SAD (SAD / patch variation) used for the outlier statistics.
constexpr std::int64_t kRelativeSadScale = 1 << 12;

// Disparity given to matches that refine to <= 0 (ORB-SLAM2): a point at (almost) infinity.
constexpr float kMinDisparityPx = 0.01f;

int patch_sum(const std::uint8_t* center, int step, int half_window) {
  int sum = 0;
  for (int dv = -half_window; dv <= half_window; ++dv) {
    for (int du = -half_window; du <= half_window; ++du) sum += center[dv * step + du];
  }
  return sum;
}

// Sum over the window of |(L - offset_L) - (R - offset_R)|, the offsets removing a brightness
// difference between the cameras (centre pixels as ORB-SLAM2, or patch means).
int normalized_sad(const std::uint8_t* left_center, int left_step, const std::uint8_t* right_center, int right_step,
                   int half_window, StereoMatcherOptions::SadNormalization normalization) {
  int offset = 0;
  if (normalization == StereoMatcherOptions::SadNormalization::kCenter) {
    offset = static_cast<int>(left_center[0]) - static_cast<int>(right_center[0]);
  } else if (normalization == StereoMatcherOptions::SadNormalization::kMean) {
    const int n = (2 * half_window + 1) * (2 * half_window + 1);
    const int difference =
        patch_sum(left_center, left_step, half_window) - patch_sum(right_center, right_step, half_window);
    offset = (difference >= 0 ? difference + n / 2 : difference - n / 2) / n;
  }
  int sad = 0;
  for (int dv = -half_window; dv <= half_window; ++dv) {
    const std::uint8_t* l = left_center + dv * left_step;
    const std::uint8_t* r = right_center + dv * right_step;
    for (int du = -half_window; du <= half_window; ++du) sad += std::abs(static_cast<int>(l[du]) - r[du] - offset);
  }
  return sad;
}

#if defined(__SSE4_1__)
// normalized_sad for windows up to 16 pixels wide, 16 pixels of a row at once: the same integer
// arithmetic, so the same result, about 5x faster. Reads up to 15 - (2w + 1) bytes past each patch
// row; the callers' patches lie inside padded pyramid levels, whose next row follows in memory.
int normalized_sad_sse(const std::uint8_t* left_center, int left_step, const std::uint8_t* right_center, int right_step,
                       int half_window, StereoMatcherOptions::SadNormalization normalization) {
  const int width = 2 * half_window + 1;
  const __m128i byte_mask = _mm_cmplt_epi8(_mm_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15),
                                           _mm_set1_epi8(static_cast<char>(width)));
  const __m128i zero = _mm_setzero_si128();
  const std::uint8_t* l0 = left_center - half_window * left_step - half_window;
  const std::uint8_t* r0 = right_center - half_window * right_step - half_window;
  auto load = [](const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); };

  int offset = 0;
  if (normalization == StereoMatcherOptions::SadNormalization::kCenter) {
    offset = static_cast<int>(left_center[0]) - static_cast<int>(right_center[0]);
  } else if (normalization == StereoMatcherOptions::SadNormalization::kMean) {
    __m128i sum_l = zero;
    __m128i sum_r = zero;
    for (int row = 0; row < width; ++row) {
      sum_l = _mm_add_epi64(sum_l, _mm_sad_epu8(_mm_and_si128(load(l0 + row * left_step), byte_mask), zero));
      sum_r = _mm_add_epi64(sum_r, _mm_sad_epu8(_mm_and_si128(load(r0 + row * right_step), byte_mask), zero));
    }
    const int n = width * width;
    const int difference = (_mm_cvtsi128_si32(sum_l) + _mm_extract_epi32(sum_l, 2)) -
                           (_mm_cvtsi128_si32(sum_r) + _mm_extract_epi32(sum_r, 2));
    offset = (difference >= 0 ? difference + n / 2 : difference - n / 2) / n;
  }
  const __m128i offset16 = _mm_set1_epi16(static_cast<short>(offset));
  const __m128i mask_lo = _mm_cvtepi8_epi16(byte_mask);
  const __m128i mask_hi = _mm_cvtepi8_epi16(_mm_srli_si128(byte_mask, 8));
  // Per lane at most 2 x 510 per row, 16 rows: fits int16.
  __m128i acc = zero;
  for (int row = 0; row < width; ++row) {
    const __m128i l = load(l0 + row * left_step);
    const __m128i r = load(r0 + row * right_step);
    const __m128i d_lo = _mm_sub_epi16(_mm_sub_epi16(_mm_cvtepu8_epi16(l), _mm_cvtepu8_epi16(r)), offset16);
    const __m128i d_hi = _mm_sub_epi16(
        _mm_sub_epi16(_mm_cvtepu8_epi16(_mm_srli_si128(l, 8)), _mm_cvtepu8_epi16(_mm_srli_si128(r, 8))), offset16);
    acc = _mm_add_epi16(acc, _mm_and_si128(_mm_abs_epi16(d_lo), mask_lo));
    acc = _mm_add_epi16(acc, _mm_and_si128(_mm_abs_epi16(d_hi), mask_hi));
  }
  const __m128i pairs = _mm_madd_epi16(acc, _mm_set1_epi16(1));
  const __m128i quads = _mm_add_epi32(pairs, _mm_srli_si128(pairs, 8));
  return _mm_cvtsi128_si32(_mm_add_epi32(quads, _mm_srli_si128(quads, 4)));
}
#endif

int window_sad(const std::uint8_t* left_center, int left_step, const std::uint8_t* right_center, int right_step,
               int half_window, StereoMatcherOptions::SadNormalization normalization) {
#if defined(__SSE4_1__)
  if (2 * half_window + 1 <= 16) {
    return normalized_sad_sse(left_center, left_step, right_center, right_step, half_window, normalization);
  }
#endif
  return normalized_sad(left_center, left_step, right_center, right_step, half_window, normalization);
}

}  // namespace

StereoMatcherOptions StereoMatcherOptions::from_yaml(const cv::FileNode& root, const std::string& source) {
  StereoMatcherOptions o;
  yaml_option::read(root, "Stereo.rowBand", source, o.row_band_px);
  if (!(o.row_band_px > 0.f) || o.row_band_px > 1000.f)
    yaml_option::fail(source, "Stereo.rowBand", "a number in (0, 1000]");
  return o;
}

StereoMatcher::StereoMatcher(const PinholeStereo& camera, const ScalePyramid& pyramid,
                             const StereoMatcherOptions& options)
    : camera_(camera), pyramid_(pyramid), options_(options) {
  // The SAD window and its search range read pixels around a keypoint on its level: they must stay
  // inside the kOrbBorderPx margin the extractor keeps readable around every level image.
  if (options.sad_half_window_px < 1 || options.sad_half_window_px > kOrbBorderPx / 2) {
    throw std::invalid_argument("StereoMatcherOptions.sad_half_window_px must be an integer in [1, " +
                                std::to_string(kOrbBorderPx / 2) + "], got " +
                                std::to_string(options.sad_half_window_px));
  }
  if (options.sad_search_px < 2 || options.sad_search_px > kOrbBorderPx / 2) {
    throw std::invalid_argument("StereoMatcherOptions.sad_search_px must be an integer in [2, " +
                                std::to_string(kOrbBorderPx / 2) + "], got " + std::to_string(options.sad_search_px));
  }
}

void StereoMatcher::match(const OrbFeatures& left, const OrbFeatures& right, std::vector<float>& u_right_px,
                          std::vector<float>& depth_m, StereoMatchStats* stats) const {
  std::vector<std::vector<int>> rows;
  prepare_rows(right, rows);
  u_right_px.assign(left.keypoints.size(), kNoStereo);
  depth_m.assign(left.keypoints.size(), kNoStereo);
  std::vector<std::pair<int, int>> sad_and_index;
  match_range(left, right, rows, 0, left.keypoints.size(), u_right_px, depth_m, sad_and_index, stats);
  reject_outliers(sad_and_index, u_right_px, depth_m, stats);
}

void StereoMatcher::prepare_rows(const OrbFeatures& right, std::vector<std::vector<int>>& rows) const {
  rows.resize(static_cast<std::size_t>(camera_.height_px));
  for (auto& r : rows) r.clear();
  for (std::size_t i = 0; i < right.keypoints.size(); ++i) {
    const Keypoint& k = right.keypoints[i];
    const float band = options_.row_band_px * pyramid_.scale[static_cast<std::size_t>(k.octave)];
    const int first = std::max(0, static_cast<int>(std::floor(k.v_px - band)));
    const int last = std::min(camera_.height_px - 1, static_cast<int>(std::ceil(k.v_px + band)));
    for (int row = first; row <= last; ++row) rows[static_cast<std::size_t>(row)].push_back(static_cast<int>(i));
  }
}

void StereoMatcher::match_range(const OrbFeatures& left, const OrbFeatures& right,
                                const std::vector<std::vector<int>>& rows, std::size_t begin, std::size_t end,
                                std::vector<float>& u_right_px, std::vector<float>& depth_m,
                                std::vector<std::pair<int, int>>& sad_and_index, StereoMatchStats* stats) const {
  StereoMatchStats local;
  StereoMatchStats& count = stats ? *stats : local;
  const float bf = static_cast<float>(camera_.bf());
  const float min_disparity = 0.f;
  const float max_disparity = static_cast<float>(camera_.fx_px) / options_.min_depth_baselines;
  const int w = options_.sad_half_window_px;
  const int L = options_.sad_search_px;
  std::vector<int> sads(static_cast<std::size_t>(2 * L + 1));

  for (std::size_t i = begin; i < end; ++i) {
    const Keypoint& kl = left.keypoints[i];
    const int row = static_cast<int>(std::lround(kl.v_px));
    const float min_u = kl.u_px - max_disparity;
    const float max_u = kl.u_px - min_disparity;
    if (row < 0 || row >= camera_.height_px || max_u < 0.f) {
      ++count.no_candidate;
      continue;
    }

    // Best right keypoint by descriptor distance among the row-band candidates.
    int best_distance = options_.max_distance + 1;
    int best_right = -1;
    const Descriptor& dl = left.descriptors[i];
    bool any_candidate = false;
    for (int j : rows[static_cast<std::size_t>(row)]) {
      const Keypoint& kr = right.keypoints[static_cast<std::size_t>(j)];
      if (kr.octave < kl.octave - 1 || kr.octave > kl.octave + 1) continue;
      if (kr.u_px < min_u || kr.u_px > max_u) continue;
      any_candidate = true;
      const int distance = hamming_distance(dl, right.descriptors[static_cast<std::size_t>(j)]);
      if (distance < best_distance) {
        best_distance = distance;
        best_right = j;
      }
    }
    if (best_right < 0) {
      ++(any_candidate ? count.over_distance : count.no_candidate);
      continue;
    }

    // Subpixel refinement by SAD on the left keypoint's level, around the matched right keypoint.
    const int level = kl.octave;
    const float inv_scale = pyramid_.inv_scale[static_cast<std::size_t>(level)];
    const cv::Mat& image_l = left.pyramid[static_cast<std::size_t>(level)];
    const cv::Mat& image_r = right.pyramid[static_cast<std::size_t>(level)];
    const int ul = static_cast<int>(std::lround(kl.u_px * inv_scale));
    const int vl = static_cast<int>(std::lround(kl.v_px * inv_scale));
    const int ur0 =
        static_cast<int>(std::lround(right.keypoints[static_cast<std::size_t>(best_right)].u_px * inv_scale));
    // The level images have kOrbBorderPx readable pixels around them.
    const int reach = w;
    if (ur0 - L - reach < -kOrbBorderPx || ur0 + L + reach >= image_r.cols + kOrbBorderPx) continue;
    if (vl - reach < -kOrbBorderPx || vl + reach >= image_l.rows + kOrbBorderPx) continue;
    if (ul - reach < -kOrbBorderPx || ul + reach >= image_l.cols + kOrbBorderPx) continue;
    const auto step_l = static_cast<int>(image_l.step1());
    const auto step_r = static_cast<int>(image_r.step1());
    const std::uint8_t* center_l = image_l.ptr<std::uint8_t>(0) + vl * step_l + ul;
    const std::uint8_t* row_r = image_r.ptr<std::uint8_t>(0) + vl * step_r;
    int best_sad = std::numeric_limits<int>::max();
    int best_shift = 0;
    for (int shift = -L; shift <= L; ++shift) {
      const int sad = window_sad(center_l, step_l, row_r + ur0 + shift, step_r, w, options_.sad_normalization);
      sads[static_cast<std::size_t>(shift + L)] = sad;
      if (sad < best_sad) {
        best_sad = sad;
        best_shift = shift;
      }
    }
    if (best_shift == -L || best_shift == L) {  // minimum at the edge: no fit possible
      ++count.sad_at_edge;
      continue;
    }

    const float s1 = static_cast<float>(sads[static_cast<std::size_t>(best_shift + L - 1)]);
    const float s2 = static_cast<float>(sads[static_cast<std::size_t>(best_shift + L)]);
    const float s3 = static_cast<float>(sads[static_cast<std::size_t>(best_shift + L + 1)]);
    float delta = 0.f;
    if (options_.subpixel_fit == StereoMatcherOptions::SubpixelFit::kParabola) {
      const float curvature = 2.f * (s1 + s3 - 2.f * s2);
      if (!(curvature > 0.f)) {
        ++count.bad_fit;
        continue;
      }
      delta = (s1 - s3) / curvature;
    } else {
      const float slope = std::max(s1, s3) - s2;
      if (!(slope > 0.f)) {
        ++count.bad_fit;
        continue;
      }
      delta = (s1 - s3) / (2.f * slope);
    }
    if (delta < -1.f || delta > 1.f) {
      ++count.bad_fit;
      continue;
    }

    float u_right = pyramid_.scale[static_cast<std::size_t>(level)] * (static_cast<float>(ur0 + best_shift) + delta);
    float disparity = kl.u_px - u_right;
    if (disparity < min_disparity || disparity >= max_disparity) {
      ++count.out_of_range;
      continue;
    }
    if (disparity <= 0.f) {
      disparity = kMinDisparityPx;
      u_right = kl.u_px - kMinDisparityPx;
    }
    u_right_px[i] = u_right;
    depth_m[i] = bf / disparity;
    int outlier_score = best_sad;
    if (options_.relative_sad_outliers) {
      // SAD relative to the left patch's own variation (sum of |L - mean L|): SAD grows with the
      // patch contrast, so absolute SAD would reject well-matched high-contrast patches first.
      const int n = (2 * w + 1) * (2 * w + 1);
      const int mean = patch_sum(center_l, step_l, w) / n;
      int variation = 0;
      for (int dv = -w; dv <= w; ++dv) {
        for (int du = -w; du <= w; ++du) variation += std::abs(static_cast<int>(center_l[dv * step_l + du]) - mean);
      }
      outlier_score =
          static_cast<int>((static_cast<std::int64_t>(best_sad) * kRelativeSadScale) / std::max(variation, 1));
    }
    sad_and_index.emplace_back(outlier_score, static_cast<int>(i));
    ++count.matched;
  }
}

void StereoMatcher::reject_outliers(std::vector<std::pair<int, int>>& sad_and_index, std::vector<float>& u_right_px,
                                    std::vector<float>& depth_m, StereoMatchStats* stats) const {
  if (sad_and_index.empty()) return;
  std::sort(sad_and_index.begin(), sad_and_index.end());
  const float median = static_cast<float>(sad_and_index[sad_and_index.size() / 2].first);
  const float threshold = options_.sad_outlier_factor * median;
  for (auto it = sad_and_index.rbegin(); it != sad_and_index.rend() && static_cast<float>(it->first) > threshold;
       ++it) {
    u_right_px[static_cast<std::size_t>(it->second)] = kNoStereo;
    depth_m[static_cast<std::size_t>(it->second)] = kNoStereo;
    if (stats) {
      ++stats->sad_outlier;
      --stats->matched;
    }
  }
}

}  // namespace heslam
