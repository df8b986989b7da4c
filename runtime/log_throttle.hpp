// Rate limit for warnings that repeat frame after frame (like ROS 2's throttled logging,
// RCLCPP_WARN_THROTTLE): per message class (a key such as "bad_frames"), the first `burst`
// occurrences are printed as they come, the last of them announcing the limit; after that at most one
// line per `period_ns`, the newest message with how many occurrences it stands for:
//   frame 7: left image is 640x480, expected 752x480
//   frame 8: left image is 640x480, expected 752x480
//   frame 9: left image ...  (further 'bad_frames' warnings: one line per 1 s)
//   frame 31: left image ... (repeated 23 times in 1.0 s)
// flush() reports occurrences still held back (at shutdown, or when a period has passed).
//
// The clock is injected (nanoseconds, monotonic) so tests can drive it. Thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace heslam::runtime {

struct LogThrottleOptions {
  // Occurrences of one class printed in full before the limit applies: the first few show what
  // is wrong and whether it varies.
  std::size_t burst = 3;
  // Afterwards at most one line per class per period (ROS 2's throttle durations are of this order).
  std::int64_t period_ns = 1'000'000'000;
};

class LogThrottle {
 public:
  using NowNs = std::function<std::int64_t()>;

  explicit LogThrottle(LogThrottleOptions options = {}, NowNs now_ns = steady_now_ns);

  // The line to print for this occurrence of `key`, or nullopt when it is held back (counted).
  std::optional<std::string> admit(std::string_view key, const std::string& message);

  // Lines for classes with held-back occurrences: all of them (`due_only` false, at shutdown) or
  // those whose period has passed since their last line (`due_only` true, from a periodic loop).
  std::vector<std::string> flush(bool due_only = false);

  static std::int64_t steady_now_ns();

 private:
  struct KeyState {
    bool seen = false;
    std::size_t printed_in_burst = 0;
    std::size_t held_back = 0;  // occurrences since the last printed line
    std::int64_t last_printed_ns = 0;
    std::int64_t last_seen_ns = 0;
    std::string latest;  // the newest held-back message
  };

  static std::string repeated_line(const KeyState& state, std::int64_t now_ns);

  LogThrottleOptions options_;
  NowNs now_ns_;
  std::mutex mutex_;
  std::map<std::string, KeyState, std::less<>> keys_;
};

}  // namespace heslam::runtime
