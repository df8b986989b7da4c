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

// How long before a frame is due to start decoding it, so that it leaves at its due time and its
// decoding does not compete with the consumers' work on the previous frame: twice a running estimate
// of one decoding (an exponential average) plus a margin. The replay's pairs and heslam-camera's
// recordings (video files, folders) use it.
class DecodeLead {
 public:
  void record(double decode_ms) { estimate_ms_ += kNewestWeight * (decode_ms - estimate_ms_); }
  std::int64_t lead_ns() const { return static_cast<std::int64_t>(kFactor * estimate_ms_ * 1e6) + kMarginNs; }

 private:
  static constexpr double kFactor = 2.0;
  static constexpr std::int64_t kMarginNs = 2'000'000;
  static constexpr double kNewestWeight = 0.2;  // weight of the newest decoding in the estimate
  double estimate_ms_ = 10.0;                   // before the first decoding: a 752x480 PNG pair
};

}  // namespace heslam
