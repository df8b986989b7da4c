// Logger output: one whole line per write(2) so lines from threads and processes never interleave.
#include "runtime/log.hpp"

#include <unistd.h>

namespace heslam::runtime {

std::optional<LogLevel> parse_log_level(std::string_view text) {
  if (text == "debug") return LogLevel::kDebug;
  if (text == "info") return LogLevel::kInfo;
  if (text == "warn") return LogLevel::kWarn;
  if (text == "error") return LogLevel::kError;
  if (text == "off") return LogLevel::kOff;
  return std::nullopt;
}

std::string_view to_string(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "debug";
    case LogLevel::kInfo: return "info";
    case LogLevel::kWarn: return "warn";
    case LogLevel::kError: return "error";
    case LogLevel::kOff: return "off";
  }
  return "unknown";
}

void Logger::write(LogLevel level, const std::string& message) const {
  std::string line = "[" + name_ + "] " + std::string(to_string(level)) + ": " + message + "\n";
  const char* data = line.data();
  std::size_t left = line.size();
  while (left > 0) {
    const ssize_t written = ::write(STDERR_FILENO, data, left);
    if (written <= 0) return;  // stderr gone: nothing sensible left to do with a log line
    data += written;
    left -= static_cast<std::size_t>(written);
  }
}

}  // namespace heslam::runtime
