// Processing statistics a component accumulates for its status: named counters and per-stage
// timing percentiles over a sliding window. Thread-safe (the status thread reads concurrently).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace heslam::runtime {

struct StageSummary {
  std::string name;
  uint64_t count = 0;  // samples in the window
  double p50_ms = 0, p90_ms = 0, p99_ms = 0, max_ms = 0;
};

class Stats {
 public:
  // window: how many most recent times per stage the percentiles cover.
  explicit Stats(std::size_t window = kDefaultWindow) : window_(window) {}

  void count(const std::string& counter, uint64_t increment = 1);
  void record_ms(const std::string& stage, double ms);

  // Times the enclosing scope: { auto timer = stats.time("extract"); ... }.
  class ScopedTimer {
   public:
    ScopedTimer(Stats& stats, std::string stage)
        : stats_(stats), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
    ~ScopedTimer() {
      stats_.record_ms(stage_,
                       std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count());
    }
    ScopedTimer(const ScopedTimer&) = delete;
    ScopedTimer& operator=(const ScopedTimer&) = delete;

   private:
    Stats& stats_;
    std::string stage_;
    std::chrono::steady_clock::time_point start_;
  };
  [[nodiscard]] ScopedTimer time(std::string stage) { return ScopedTimer(*this, std::move(stage)); }

  std::map<std::string, uint64_t> counters() const;
  std::vector<StageSummary> stages() const;  // sorted by name

 private:
  // ~1 minute of 20 Hz frames: recent enough to show a slowdown, large enough for a stable p99.
  static constexpr std::size_t kDefaultWindow = 1000;

  struct Ring {
    std::vector<double> values_ms;
    std::size_t next = 0;
  };
  std::size_t window_;
  mutable std::mutex mutex_;
  std::map<std::string, uint64_t> counters_;
  std::map<std::string, Ring> stages_;
};

}  // namespace heslam::runtime
