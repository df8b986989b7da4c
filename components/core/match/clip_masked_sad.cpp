// Clip-masked SAD: masks of the left window and the right search strip, then one scalar pass per shift.
#include "components/core/match/clip_masked_sad.hpp"

#include <cstdlib>

namespace heslam {
namespace {

// Clipped: the pixel or one of its 4-neighbours at or above the image's clip level.
bool clipped_near(const std::uint8_t* p, int step, int top) {
  return p[0] >= top || p[-1] >= top || p[1] >= top || p[-step] >= top || p[step] >= top;
}

}  // namespace

ClipMaskedSad::ClipMaskedSad(int half_window_px, int search_px)
    : w_(half_window_px),
      search_(search_px),
      clipped_l_(static_cast<std::size_t>((2 * half_window_px + 1) * (2 * half_window_px + 1))),
      clipped_r_(static_cast<std::size_t>((2 * half_window_px + 1) * (2 * half_window_px + 1 + 2 * search_px))) {}

bool ClipMaskedSad::compute(const std::uint8_t* center_l, int step_l, const std::uint8_t* row_r, int ur0, int step_r,
                            const ClipLevels& levels, std::vector<int>& sads) {
  const int window = 2 * w_ + 1;
  const int span = window + 2 * search_;
  bool any = false;
  for (int dv = -w_; dv <= w_; ++dv) {
    const std::uint8_t* l = center_l + dv * step_l;
    for (int du = -w_; du <= w_; ++du) {
      const bool c = clipped_near(l + du, step_l, levels.left_top);
      clipped_l_[static_cast<std::size_t>((dv + w_) * window + du + w_)] = c ? 1 : 0;
      any = any || c;
    }
    const std::uint8_t* r = row_r + dv * step_r + ur0 - search_ - w_;
    for (int du = 0; du < span; ++du) {
      const bool c = clipped_near(r + du, step_r, levels.right_top);
      clipped_r_[static_cast<std::size_t>((dv + w_) * span + du)] = c ? 1 : 0;
      any = any || c;
    }
  }
  if (!any) return false;
  const int n = window * window;
  std::vector<int> costs(static_cast<std::size_t>(2 * search_ + 1));
  // A pixel pair takes part when neither camera clipped it (or its neighbours).
  const auto usable = [&](int dv, int du, int shift) {
    return clipped_l_[static_cast<std::size_t>((dv + w_) * window + du + w_)] == 0 &&
           clipped_r_[static_cast<std::size_t>((dv + w_) * span + du + w_ + shift + search_)] == 0;
  };
  for (int shift = -search_; shift <= search_; ++shift) {
    // Mean normalization over the usable pixels, then SAD over them.
    int used = 0;
    int sum_l = 0;
    int sum_r = 0;
    for (int dv = -w_; dv <= w_; ++dv) {
      const std::uint8_t* l = center_l + dv * step_l;
      const std::uint8_t* r = row_r + dv * step_r + ur0 + shift;
      for (int du = -w_; du <= w_; ++du) {
        if (!usable(dv, du, shift)) continue;
        ++used;
        sum_l += l[du];
        sum_r += r[du];
      }
    }
    if (2 * used < n) return false;
    const int difference = sum_l - sum_r;
    const int offset = (difference >= 0 ? difference + used / 2 : difference - used / 2) / used;
    int sad = 0;
    for (int dv = -w_; dv <= w_; ++dv) {
      const std::uint8_t* l = center_l + dv * step_l;
      const std::uint8_t* r = row_r + dv * step_r + ur0 + shift;
      for (int du = -w_; du <= w_; ++du) {
        if (!usable(dv, du, shift)) continue;
        sad += std::abs(static_cast<int>(l[du]) - r[du] - offset);
      }
    }
    costs[static_cast<std::size_t>(shift + search_)] = (sad * n + used / 2) / used;
  }
  sads = costs;
  return true;
}

}  // namespace heslam
