// Left/right pairing by stamp for two free-running image streams (two devices, two files): the
// next two images whose stamps differ by at most a tolerance form a pair; an image older than its
// counterpart by more is unpaired, counted, and the next one of its stream is read. DDS-free and
// clock-free, so it is tested exactly.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <optional>
#include <utility>

namespace heslam {

struct PairingCounts {
  std::size_t unpaired_left = 0;
  std::size_t unpaired_right = 0;
};

// next_left / next_right: the stream's next item, nothing at its end; stamp_of: the item's stamp.
// Returns the next pair, or nothing when either stream ended (its partner, if read, is counted).
template <typename Item>
std::optional<std::pair<Item, Item>> next_stereo_pair(const std::function<std::optional<Item>()>& next_left,
                                                      const std::function<std::optional<Item>()>& next_right,
                                                      const std::function<std::int64_t(const Item&)>& stamp_of,
                                                      std::int64_t tolerance_ns, PairingCounts& counts) {
  std::optional<Item> left = next_left();
  std::optional<Item> right = left ? next_right() : std::nullopt;
  while (left && right) {
    const std::int64_t left_ns = stamp_of(*left);
    const std::int64_t right_ns = stamp_of(*right);
    if (std::llabs(left_ns - right_ns) <= tolerance_ns)
      return std::pair<Item, Item>(std::move(*left), std::move(*right));
    if (left_ns < right_ns) {
      ++counts.unpaired_left;
      left = next_left();
    } else {
      ++counts.unpaired_right;
      right = next_right();
    }
  }
  if (left) ++counts.unpaired_left;
  if (right) ++counts.unpaired_right;
  return std::nullopt;
}

}  // namespace heslam
