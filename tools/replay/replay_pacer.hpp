// When each frame of a replay is due on the wall clock: recorded time scaled by the rate, with
// pauses shifting everything after them. DDS-free and clock-free (times are passed in) so it is
// tested exactly.
#pragma once

#include <cstdint>

namespace heslam {

class ReplayPacer {
 public:
  // rate: 1 = real time, 2 = twice as fast, <= 0 = as fast as possible (every frame due at once).
  explicit ReplayPacer(double rate);

  // (Re)anchors: the frame stamped first_stamp_ns is due at now_ns (start, and each --loop pass).
  void start(std::int64_t first_stamp_ns, std::int64_t now_ns);

  // Wall time at which the frame stamped stamp_ns is due (while paused: never, INT64_MAX).
  std::int64_t due_ns(std::int64_t stamp_ns) const;

  void pause(std::int64_t now_ns);
  void resume(std::int64_t now_ns);
  bool paused() const { return paused_; }

  double rate() const { return rate_; }

 private:
  double rate_;
  std::int64_t first_stamp_ns_ = 0;
  std::int64_t anchor_ns_ = 0;  // wall time of the first frame, moved later by each pause
  std::int64_t paused_at_ns_ = 0;
  bool paused_ = false;
};

}  // namespace heslam
