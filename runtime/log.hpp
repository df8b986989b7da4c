// Leveled logging to stderr, one line per message, prefixed by the component name:
//   "[frontend] warn: frame 17: only 34 keypoints"
#pragma once

#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace heslam::runtime {

enum class LogLevel { kDebug, kInfo, kWarn, kError, kOff };

// "debug" | "info" | "warn" | "error" | "off"; nullopt for anything else.
std::optional<LogLevel> parse_log_level(std::string_view text);
std::string_view to_string(LogLevel level);

class Logger {
 public:
  explicit Logger(std::string name, LogLevel level = LogLevel::kInfo) : name_(std::move(name)), level_(level) {}

  // Streams every argument: log.info("frame ", seq, " took ", ms, " ms").
  template <typename... Args>
  void debug(const Args&... args) const { log(LogLevel::kDebug, args...); }
  template <typename... Args>
  void info(const Args&... args) const { log(LogLevel::kInfo, args...); }
  template <typename... Args>
  void warn(const Args&... args) const { log(LogLevel::kWarn, args...); }
  template <typename... Args>
  void error(const Args&... args) const { log(LogLevel::kError, args...); }

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
};

}  // namespace heslam::runtime
