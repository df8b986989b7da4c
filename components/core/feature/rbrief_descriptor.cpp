// rBRIEF tests: one at a time, or 16 at a time with the sampled pixels inserted into byte lanes
// (SSE4.1). Tried and slower: 8-pixel vpgatherdd (extract4), and bytes stored to two arrays then
// compared 32 at a time (the byte stores cannot forward to the vector load: twice the time).
#include "components/core/feature/rbrief_descriptor.hpp"

#include <cstddef>
#include <cstring>
#include <utility>

#if defined(__SSE4_1__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

#if defined(__SSE4_1__)
// Tests per vector: one byte lane each, so the 16-bit movemask is 2 descriptor bytes in order.
constexpr std::size_t kLanes = 16;
static_assert(kOrbPattern.size() % kLanes == 0, "whole vectors of tests");

// The pixels of tests t .. t + 15 into the lanes of `first` and `second` (pinsrb takes an immediate
// lane index, hence the unrolling over an index sequence).
template <std::size_t... lane>
[[gnu::always_inline]] inline void sample_lanes(const std::uint8_t* center, const int* first_offsets,
                                                const int* second_offsets, __m128i& first, __m128i& second,
                                                std::index_sequence<lane...>) {
  ((first = _mm_insert_epi8(first, center[first_offsets[lane]], lane),
    second = _mm_insert_epi8(second, center[second_offsets[lane]], lane)),
   ...);
}
#endif

}  // namespace

Descriptor rbrief_descriptor_scalar(const std::uint8_t* center, const RotatedOrbPattern& offsets) {
  Descriptor d{};
  for (std::size_t byte = 0; byte < d.size(); ++byte) {
    std::uint8_t bits = 0;
    for (std::size_t bit = 0; bit < 8; ++bit) {
      const std::size_t t = byte * 8 + bit;
      bits |= static_cast<std::uint8_t>((center[offsets.first[t]] < center[offsets.second[t]]) << bit);
    }
    d[byte] = bits;
  }
  return d;
}

Descriptor rbrief_descriptor(const std::uint8_t* center, const RotatedOrbPattern& offsets) {
#if defined(__SSE4_1__)
  Descriptor d{};
  for (std::size_t t = 0; t < kOrbPattern.size(); t += kLanes) {
    __m128i first = _mm_setzero_si128();
    __m128i second = _mm_setzero_si128();
    sample_lanes(center, &offsets.first[t], &offsets.second[t], first, second, std::make_index_sequence<kLanes>{});
    // first >= second exactly when max(first, second) == first (unsigned); the test's bit is the opposite.
    const __m128i not_darker = _mm_cmpeq_epi8(_mm_max_epu8(first, second), first);
    const auto bits = static_cast<std::uint16_t>(~_mm_movemask_epi8(not_darker));
    std::memcpy(d.data() + t / 8, &bits, sizeof(bits));
  }
  return d;
#else
  return rbrief_descriptor_scalar(center, offsets);
#endif
}

}  // namespace heslam
