// SAD over the pixels of a window that neither camera clipped (issue 17 §1, cameras exposed apart).
//
// Where one camera saturates, the edge of its saturated plateau lies where its exposure put it; the
// other camera's plateau (its own saturation, or the left clipped to the right's range by
// HE.stereo: matched) has its edge elsewhere. A window containing both edges is pulled by their
// offset, whatever the cost compares (docs/benchmarks.md, issue 17 §1). Here the pixels at either
// image's clip level, and their 4-neighbours (the pyramid's resampling blurs a plateau's edge by a
// pixel), are left out of the cost; the SAD of the remaining pixels is scaled to the full window,
// so that shifts with different numbers of usable pixels stay comparable.
#pragma once

#include <cstdint>
#include <vector>

namespace heslam {

// Grey levels at or above which a pyramid level image counts as clipped; 256 = not clipped.
struct ClipLevels {
  int left_top = 256;
  int right_top = 256;
  bool any() const { return left_top < 256 || right_top < 256; }
};

class ClipMaskedSad {
 public:
  ClipMaskedSad(int half_window_px, int search_px);

  // Costs of the left window at center_l against the right windows centred at row_r + ur0 + shift,
  // shift in [-search, search], into sads (size 2 search + 1), mean-normalized over the usable
  // pixels. Returns false (sads untouched) when no pixel of the windows is clipped, or when some
  // shift keeps fewer than half of the window's pixels: the plain SAD then applies.
  bool compute(const std::uint8_t* center_l, int step_l, const std::uint8_t* row_r, int ur0, int step_r,
               const ClipLevels& levels, std::vector<int>& sads);

 private:
  int w_;
  int search_;
  std::vector<std::uint8_t> clipped_l_;  // window x window
  std::vector<std::uint8_t> clipped_r_;  // window x (window + 2 search)
};

}  // namespace heslam
