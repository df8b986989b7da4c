// FAST-9 score map: the arc test and OpenCV's cornerScore as one branch-free min/max network over
// saturated differences, for 64, 32 or 16 pixels at a time (AVX-512BW, AVX2, SSE2; scalar elsewhere).
#include "components/core/feature/fast_score_map.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <stdexcept>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

// The 16-pixel Bresenham circle of radius 3 in circular order (as cv::FAST's TYPE_9_16), (dx, dy).
constexpr std::array<std::array<int, 2>, 16> kCircle = {{{0, 3},
                                                         {1, 3},
                                                         {2, 2},
                                                         {3, 1},
                                                         {3, 0},
                                                         {3, -1},
                                                         {2, -2},
                                                         {1, -3},
                                                         {0, -3},
                                                         {-1, -3},
                                                         {-2, -2},
                                                         {-3, -1},
                                                         {-3, 0},
                                                         {-3, 1},
                                                         {-2, 2},
                                                         {-1, 3}}};

// The circle's rows are those of the centre -3 .. +3: rows[kRadiusRows + dy].
constexpr int kRadiusRows = FastScoreMap::kRadiusPx;

struct ScalarLanes {
  using V = std::uint8_t;
  static constexpr int kWidth = 1;
  static V load(const std::uint8_t* p) { return *p; }
  static void store(std::uint8_t* p, V v) { *p = v; }
  static V min(V a, V b) { return std::min(a, b); }
  static V max(V a, V b) { return std::max(a, b); }
  static V subs(V a, V b) { return static_cast<V>(a > b ? a - b : 0); }
  static V splat(std::uint8_t x) { return x; }
};

#if defined(__AVX512BW__)
struct SimdLanes {
  using V = __m512i;
  static constexpr int kWidth = 64;
  static V load(const std::uint8_t* p) { return _mm512_loadu_si512(p); }
  static void store(std::uint8_t* p, V v) { _mm512_storeu_si512(p, v); }
  static V min(V a, V b) { return _mm512_min_epu8(a, b); }
  static V max(V a, V b) { return _mm512_max_epu8(a, b); }
  static V subs(V a, V b) { return _mm512_subs_epu8(a, b); }
  static V splat(std::uint8_t x) { return _mm512_set1_epi8(static_cast<char>(x)); }
};
#elif defined(__AVX2__)
struct SimdLanes {
  using V = __m256i;
  static constexpr int kWidth = 32;
  static V load(const std::uint8_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
  static void store(std::uint8_t* p, V v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
  static V min(V a, V b) { return _mm256_min_epu8(a, b); }
  static V max(V a, V b) { return _mm256_max_epu8(a, b); }
  static V subs(V a, V b) { return _mm256_subs_epu8(a, b); }
  static V splat(std::uint8_t x) { return _mm256_set1_epi8(static_cast<char>(x)); }
};
#elif defined(__SSE2__)
struct SimdLanes {
  using V = __m128i;
  static constexpr int kWidth = 16;
  static V load(const std::uint8_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
  static void store(std::uint8_t* p, V v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
  static V min(V a, V b) { return _mm_min_epu8(a, b); }
  static V max(V a, V b) { return _mm_max_epu8(a, b); }
  static V subs(V a, V b) { return _mm_subs_epu8(a, b); }
  static V splat(std::uint8_t x) { return _mm_set1_epi8(static_cast<char>(x)); }
};
#else
using SimdLanes = ScalarLanes;
#endif

// FAST-9 on the circle's pixels p[0 .. 15] around the centre v. Saturating subtraction is monotone,
// so the weakest difference of an arc is one subtraction from the arc's extreme pixel
// (min_k (p_k -sat v) = (min_k p_k) -sat v; min_k (v -sat p_k) = v -sat max_k p_k), and likewise the
// best arc's: the network runs on the pixels and subtracts once per polarity, with no per-pixel
// differences (16 loads instead of 16 loads and 32 subtractions, half the live vectors).
//
// best over the 16 arcs of 9 contiguous circle pixels of worst over the arc's pixels, with (worst,
// best) = (min, max) for the brighter polarity and (max, min) for the darker one. The arcs starting
// at 2j and 2j + 1 share the 8 pixels 2j + 1 .. 2j + 8, so only those 8 extremes (from extremes of 2
// and 4 at odd starts) are built, and best(worst(m, p[2j]), worst(m, p[2j + 9])) is taken as
// worst(m, best(p[2j], p[2j + 9])) (min and max distribute over each other): 47 min/max per polarity
// instead of 80, the same value.
template <class L, class Worst, class Best>
[[gnu::always_inline]] inline typename L::V best_arc(const typename L::V (&p)[16], Worst worst, Best best) {
  // Plain arrays: std::array of a vector type drops its alignment attribute.
  typename L::V worst2[8];  // worst2[j]: pixels 2j + 1 .. 2j + 2
  typename L::V worst4[8];  // worst4[j]: pixels 2j + 1 .. 2j + 4
  for (int j = 0; j < 8; ++j) worst2[j] = worst(p[2 * j + 1], p[(2 * j + 2) & 15]);
  for (int j = 0; j < 8; ++j) worst4[j] = worst(worst2[j], worst2[(j + 1) & 7]);
  typename L::V result = p[0];
  for (int j = 0; j < 8; ++j) {
    const typename L::V worst8 = worst(worst4[j], worst4[(j + 2) & 7]);  // pixels 2j + 1 .. 2j + 8
    const typename L::V two_arcs = worst(worst8, best(p[2 * j], p[(2 * j + 9) & 15]));
    result = j == 0 ? two_arcs : best(result, two_arcs);
  }
  return result;
}

// Scores of L::kWidth consecutive pixels starting at column x of the circle's 7 rows (rows[3] is the
// centre row). Row pointers plus constant column offsets let every circle load be one addressing mode
// (no per-pixel offset table read), and inlining keeps the rows in registers across a whole row.
// The strength of a polarity is its best arc's weakest difference; a corner at threshold t has an arc
// whose differences all exceed t, i.e. strength >= t + 1, and cv::FAST reports strength - 1 as its
// score.
template <class L>
[[gnu::always_inline]] inline void score_lanes(const std::uint8_t* const (&rows)[2 * kRadiusRows + 1], std::ptrdiff_t x,
                                               std::uint8_t* out) {
  using V = typename L::V;
  const V v = L::load(rows[kRadiusRows] + x);
  V p[16];
  for (int k = 0; k < 16; ++k) p[k] = L::load(rows[kRadiusRows + kCircle[k][1]] + x + kCircle[k][0]);
  const auto min = [](V a, V b) { return L::min(a, b); };
  const auto max = [](V a, V b) { return L::max(a, b); };
  const V brighter = L::subs(best_arc<L>(p, min, max), v);  // max over arcs of min_k (p_k -sat v)
  const V darker = L::subs(v, best_arc<L>(p, max, min));    // max over arcs of min_k (v -sat p_k)
  L::store(out, L::subs(L::max(brighter, darker), L::splat(1)));
}

// Bit k set when p[k] >= t, for kMaskWidth bytes.
using MaskBits = std::uint32_t;
#if defined(__AVX2__)
constexpr int kMaskWidth = 32;
MaskBits at_least(const std::uint8_t* p, std::uint8_t t) {
  const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
  const __m256i at_least_t = _mm256_cmpeq_epi8(_mm256_max_epu8(v, _mm256_set1_epi8(static_cast<char>(t))), v);
  return static_cast<MaskBits>(_mm256_movemask_epi8(at_least_t));
}
#elif defined(__SSE2__)
constexpr int kMaskWidth = 16;
MaskBits at_least(const std::uint8_t* p, std::uint8_t t) {
  const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
  const __m128i at_least_t = _mm_cmpeq_epi8(_mm_max_epu8(v, _mm_set1_epi8(static_cast<char>(t))), v);
  return static_cast<MaskBits>(_mm_movemask_epi8(at_least_t));
}
#else
constexpr int kMaskWidth = 1;
MaskBits at_least(const std::uint8_t* p, std::uint8_t t) { return *p >= t ? 1u : 0u; }
#endif

// Bit k set when p[k] is strictly greater than its 8 neighbours (only its left and right ones when
// !up and !down, the row above when up, the row below when down), for kMaskWidth bytes: the 3x3
// non-maximum suppression of a whole vector of candidates at once. p[-1] .. p[kMaskWidth] and,
// as asked, the same columns stride bytes above / below must be readable.
#if defined(__AVX2__)
constexpr bool kVectorMaxima = true;
MaskBits strict_maxima(const std::uint8_t* p, std::ptrdiff_t stride, bool up, bool down) {
  const auto load = [](const std::uint8_t* q) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(q)); };
  const __m256i s = load(p);
  // n >= s exactly when max(n, s) == n: such a neighbour suppresses the pixel.
  const auto not_below = [&](const std::uint8_t* q) {
    const __m256i n = load(q);
    return _mm256_cmpeq_epi8(_mm256_max_epu8(n, s), n);
  };
  __m256i suppressed = _mm256_or_si256(not_below(p - 1), not_below(p + 1));
  for (const std::ptrdiff_t row : {up ? -stride : std::ptrdiff_t{0}, down ? stride : std::ptrdiff_t{0}}) {
    if (row == 0) continue;
    suppressed = _mm256_or_si256(suppressed, not_below(p + row - 1));
    suppressed = _mm256_or_si256(suppressed, not_below(p + row));
    suppressed = _mm256_or_si256(suppressed, not_below(p + row + 1));
  }
  return ~static_cast<MaskBits>(_mm256_movemask_epi8(suppressed));
}
#elif defined(__SSE2__)
constexpr bool kVectorMaxima = true;
MaskBits strict_maxima(const std::uint8_t* p, std::ptrdiff_t stride, bool up, bool down) {
  const auto load = [](const std::uint8_t* q) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(q)); };
  const __m128i s = load(p);
  const auto not_below = [&](const std::uint8_t* q) {
    const __m128i n = load(q);
    return _mm_cmpeq_epi8(_mm_max_epu8(n, s), n);
  };
  __m128i suppressed = _mm_or_si128(not_below(p - 1), not_below(p + 1));
  for (const std::ptrdiff_t row : {up ? -stride : std::ptrdiff_t{0}, down ? stride : std::ptrdiff_t{0}}) {
    if (row == 0) continue;
    suppressed = _mm_or_si128(suppressed, not_below(p + row - 1));
    suppressed = _mm_or_si128(suppressed, not_below(p + row));
    suppressed = _mm_or_si128(suppressed, not_below(p + row + 1));
  }
  return static_cast<MaskBits>(~_mm_movemask_epi8(suppressed) & 0xFFFF);
}
#else
constexpr bool kVectorMaxima = false;
MaskBits strict_maxima(const std::uint8_t*, std::ptrdiff_t, bool, bool) { return 0; }
#endif

}  // namespace

void FastScoreMap::compute(const cv::Mat& image, const cv::Rect& area) {
  if (image.type() != CV_8UC1) throw std::invalid_argument("FastScoreMap: expected an 8-bit grey image");
  // The circle reads kRadiusPx around the area; a view into a larger (padded) image may read its
  // parent's pixels, as cv::FAST on a sub-image does.
  cv::Size whole;
  cv::Point offset;
  image.locateROI(whole, offset);
  const cv::Rect readable(-offset.x + kRadiusPx, -offset.y + kRadiusPx, whole.width - 2 * kRadiusPx,
                          whole.height - 2 * kRadiusPx);
  if (area.width <= 0 || area.height <= 0 || (area & readable) != area) {
    throw std::invalid_argument("FastScoreMap: the area and a 3-pixel ring around it must lie inside the image");
  }
  area_ = area;
  // kMaskWidth bytes of slack: corners() reads a whole vector where a row's region ends.
  score_.resize(static_cast<std::size_t>(area.width) * static_cast<std::size_t>(area.height) + kMaskWidth);
  const auto step = static_cast<std::ptrdiff_t>(image.step1());
  constexpr int lanes = SimdLanes::kWidth;
  for (int row = 0; row < area.height; ++row) {
    const std::uint8_t* centre = image.ptr<std::uint8_t>(area.y + row) + area.x;
    const std::uint8_t* rows[2 * kRadiusRows + 1];
    for (int dy = -kRadiusRows; dy <= kRadiusRows; ++dy) rows[kRadiusRows + dy] = centre + dy * step;
    std::uint8_t* out = &score_[static_cast<std::size_t>(row) * static_cast<std::size_t>(area.width)];
    int x = 0;
    for (; x + lanes <= area.width; x += lanes) score_lanes<SimdLanes>(rows, x, out + x);
    if (x == area.width) continue;
    if (area.width >= lanes) {
      // The tail as one more full vector ending at the last pixel: a few pixels are scored twice.
      score_lanes<SimdLanes>(rows, area.width - lanes, out + area.width - lanes);
    } else {
      for (; x < area.width; ++x) score_lanes<ScalarLanes>(rows, x, out + x);
    }
  }
}

void FastScoreMap::corners(const cv::Rect& region, int threshold, std::vector<ScoredPoint>& out) const {
  if ((region & area_) != region) throw std::invalid_argument("FastScoreMap::corners: region outside the scored area");
  if (threshold < 1) throw std::invalid_argument("FastScoreMap::corners: expected threshold >= 1");
  if (region.width <= 0 || region.height <= 0) return;
  const auto t = static_cast<std::uint8_t>(std::min(threshold, 255));
  const auto stride = static_cast<std::ptrdiff_t>(area_.width);
  const int last_x = region.width - 1;
  for (int y = region.y; y < region.y + region.height; ++y) {
    const std::uint8_t* row = &score_[static_cast<std::size_t>(y - area_.y) * static_cast<std::size_t>(stride) +
                                      static_cast<std::size_t>(region.x - area_.x)];
    // cv::FAST on the region sees no corners outside it: those neighbours count as 0 and a
    // candidate (score >= t >= 1) beats them, so they are simply not compared.
    const bool has_up = y > region.y;
    const bool has_down = y + 1 < region.y + region.height;
    auto consider = [&](int i) {
      const std::uint8_t s = row[i];
      const int lo = i > 0 ? -1 : 0;
      const int hi = i < last_x ? 1 : 0;
      bool is_max = (lo == 0 || s > row[i - 1]) && (hi == 0 || s > row[i + 1]);
      for (int dx = lo; is_max && dx <= hi; ++dx) {
        if (has_up && !(s > row[i + dx - stride])) is_max = false;
        if (has_down && !(s > row[i + dx + stride])) is_max = false;
      }
      if (is_max) out.push_back({static_cast<float>(region.x + i), static_cast<float>(y), static_cast<float>(s)});
    };
    // Most pixels score below the threshold: find the candidates a vector at a time, in order. Where
    // the vector's left and right neighbours are inside the region, suppress non-maxima a vector at
    // a time too (the same comparisons as consider's).
    int i = 0;
    for (; i + kMaskWidth <= region.width; i += kMaskWidth) {
      MaskBits bits = at_least(row + i, t);
      if (bits == 0) continue;
      if (kVectorMaxima && i >= 1 && i + kMaskWidth + 1 <= region.width) {
        for (bits &= strict_maxima(row + i, stride, has_up, has_down); bits != 0; bits &= bits - 1) {
          const int x = i + std::countr_zero(bits);
          out.push_back({static_cast<float>(region.x + x), static_cast<float>(y), static_cast<float>(row[x])});
        }
        continue;
      }
      for (; bits != 0; bits &= bits - 1) consider(i + std::countr_zero(bits));
    }
    // The rest of the row (narrower than a vector: all of a grid cell's row) as one vector too, the
    // bits past the region's end masked off (score_ has a vector of slack after its last row).
    if (i <= last_x) {
      const int rest = region.width - i;  // < kMaskWidth <= 32
      const MaskBits inside = (MaskBits{1} << rest) - 1;
      for (MaskBits bits = at_least(row + i, t) & inside; bits != 0; bits &= bits - 1) {
        consider(i + std::countr_zero(bits));
      }
    }
  }
}

}  // namespace heslam
