// Leveled logging to stderr, one line per message, prefixed by the component name:
//   "[frontend] warn: frame 17: only 34 keypoints"
// warn_throttled(key, ...) is for warnings that can repeat every frame: per key, a few lines, then at
// most one per second with a count (runtime/log_throttle.hpp); flush_throttled() reports the rest.
#pragma once

#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

#include "runtime/log_throttle.hpp"

namespace heslam::runtime {

enum class LogLevel { kDebug, kInfo, kWarn, kError, kOff };

// "debug" | "info" | "warn" | "error" | "off"; nullopt for anything else.
std::optional<LogLevel> parse_log_level(std::string_view text);
std::string_view to_string(LogLevel level);

class Logger {
 public:
  explicit Logger(std::string name, LogLevel level = LogLevel::kInfo,
                  std::shared_ptr<LogThrottle> throttle = std::make_shared<LogThrottle>())
      : name_(std::move(name)), level_(level), throttle_(std::move(throttle)) {}

  // Streams every argument: log.info("frame ", seq, " took ", ms, " ms").
  template <typename... Args>
  void debug(const Args&... args) const {
    log(LogLevel::kDebug, args...);
  }
  template <typename... Args>
  void info(const Args&... args) const {
    log(LogLevel::kInfo, args...);
  }
  template <typename... Args>
  void warn(const Args&... args) const {
    log(LogLevel::kWarn, args...);
  }
  template <typename... Args>
  void error(const Args&... args) const {
    log(LogLevel::kError, args...);
  }

  // A warning of class `key` (e.g. the stats counter it goes with, "bad_frames") that may repeat per
  // frame: the first few are printed, then one line per second saying how many it stands for.
  template <typename... Args>
  void warn_throttled(std::string_view key, const Args&... args) const {
    if (!enabled(LogLevel::kWarn)) return;
    std::ostringstream line;
    (line << ... << args);
    if (auto admitted = throttle_->admit(key, line.str())) write(LogLevel::kWarn, *admitted);
  }
  // Prints the counts of throttled warnings held back: all (at exit) or those due (periodically).
  void flush_throttled(bool due_only = false) const {
    for (const std::string& line : throttle_->flush(due_only)) {
      if (enabled(LogLevel::kWarn)) write(LogLevel::kWarn, line);
    }
  }

  template <typename... Args>
  void log(LogLevel level, const Args&... args) const {
    if (!enabled(level)) return;
    std::ostringstream line;
    (line << ... << args);
    write(level, line.str());
  }

  bool enabled(LogLevel level) const { return level >= level_ && level != LogLevel::kOff; }
  void set_level(LogLevel level) { level_ = level; }
  LogLevel level() const { return level_; }
  const std::string& name() const { return name_; }

 private:
  void write(LogLevel level, const std::string& message) const;  // whole line in one write (threads, pipes)

  std::string name_;
  LogLevel level_;
  std::shared_ptr<LogThrottle> throttle_;  // shared by copies of this logger
};

}  // namespace heslam::runtime
