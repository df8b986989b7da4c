// Statistics over the last N arrivals of a topic: the rate and period spread (`heslam-spy hz`, like
// `ros2 topic hz`) and the byte rate (`heslam-spy bw`). DDS-free so it is tested on exact stamps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>

namespace heslam {

struct RateStats {
  std::size_t periods = 0;  // periods in the window (arrivals - 1)
  double rate_hz = 0.0;     // periods / (last - first arrival)
  double min_period_s = 0.0;
  double max_period_s = 0.0;
  double std_period_s = 0.0;  // population standard deviation of the periods
};

struct BandwidthStats {
  std::size_t samples = 0;
  double bytes_per_s = 0.0;  // bytes of all but the first arrival / (last - first arrival)
  double mean_bytes = 0.0;   // per sample, over the whole window
  std::size_t min_bytes = 0;
  std::size_t max_bytes = 0;
};

class ArrivalWindow {
 public:
  // window: how many arrivals are kept (>= 2).
  explicit ArrivalWindow(std::size_t window);

  // One sample arrived at arrival_ns (any monotonic clock) carrying `bytes` serialized bytes.
  void add(std::int64_t arrival_ns, std::size_t bytes);

  std::size_t size() const { return arrivals_.size(); }
  RateStats rate() const;
  BandwidthStats bandwidth() const;

 private:
  struct Arrival {
    std::int64_t arrival_ns;
    std::size_t bytes;
  };
  std::size_t window_;
  std::deque<Arrival> arrivals_;
};

}  // namespace heslam
