// Per-class rate limit for repeated log lines: a burst, then one line per period with a count.
#include "runtime/log_throttle.hpp"

#include <chrono>
#include <cstdio>

namespace heslam::runtime {

LogThrottle::LogThrottle(LogThrottleOptions options, NowNs now_ns) : options_(options), now_ns_(std::move(now_ns)) {}

std::int64_t LogThrottle::steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string LogThrottle::repeated_line(const KeyState& state, std::int64_t now_ns) {
  char suffix[96];
  std::snprintf(suffix, sizeof suffix, " (repeated %zu time%s in %.1f s)", state.held_back,
                state.held_back == 1 ? "" : "s", static_cast<double>(now_ns - state.last_printed_ns) * 1e-9);
  return state.latest + suffix;
}

std::optional<std::string> LogThrottle::admit(std::string_view key, const std::string& message) {
  const std::lock_guard lock(mutex_);
  const std::int64_t now = now_ns_();
  auto found = keys_.find(key);
  if (found == keys_.end()) found = keys_.emplace(std::string(key), KeyState{}).first;
  KeyState& state = found->second;
  // A class quiet for a whole period, with nothing held back, starts a new burst.
  if (state.seen && state.held_back == 0 && now - state.last_seen_ns >= options_.period_ns) state.printed_in_burst = 0;
  state.seen = true;
  state.last_seen_ns = now;
  if (state.printed_in_burst < options_.burst) {
    ++state.printed_in_burst;
    state.last_printed_ns = now;
    if (state.printed_in_burst < options_.burst) return message;
    char limit[96];
    std::snprintf(limit, sizeof limit, "' warnings: one line per %g s)",
                  static_cast<double>(options_.period_ns) * 1e-9);
    return message + " (further '" + std::string(key) + limit;
  }
  ++state.held_back;
  state.latest = message;
  if (now - state.last_printed_ns < options_.period_ns) return std::nullopt;
  std::string line = repeated_line(state, now);
  state.held_back = 0;
  state.last_printed_ns = now;
  return line;
}

std::vector<std::string> LogThrottle::flush(bool due_only) {
  const std::lock_guard lock(mutex_);
  const std::int64_t now = now_ns_();
  std::vector<std::string> lines;
  for (auto& [key, state] : keys_) {
    if (state.held_back == 0) continue;
    if (due_only && now - state.last_printed_ns < options_.period_ns) continue;
    lines.push_back(repeated_line(state, now));
    state.held_back = 0;
    state.last_printed_ns = now;
  }
  return lines;
}

}  // namespace heslam::runtime
