// Wall-clock schedule of a replay with a rate and pauses.
#include "tools/replay/replay_pacer.hpp"

#include <cmath>
#include <limits>

namespace heslam {

ReplayPacer::ReplayPacer(double rate) : rate_(rate) {}

void ReplayPacer::start(std::int64_t first_stamp_ns, std::int64_t now_ns) {
  first_stamp_ns_ = first_stamp_ns;
  anchor_ns_ = now_ns;
  if (paused_) paused_at_ns_ = now_ns;
}

std::int64_t ReplayPacer::due_ns(std::int64_t stamp_ns) const {
  if (paused_) return std::numeric_limits<std::int64_t>::max();
  if (rate_ <= 0.0) return anchor_ns_;
  const double since_first_ns = static_cast<double>(stamp_ns - first_stamp_ns_);
  return anchor_ns_ + static_cast<std::int64_t>(std::llround(since_first_ns / rate_));
}

void ReplayPacer::pause(std::int64_t now_ns) {
  if (paused_) return;
  paused_ = true;
  paused_at_ns_ = now_ns;
}

void ReplayPacer::resume(std::int64_t now_ns) {
  if (!paused_) return;
  paused_ = false;
  anchor_ns_ += now_ns - paused_at_ns_;  // the schedule continues where it stopped
}

}  // namespace heslam
