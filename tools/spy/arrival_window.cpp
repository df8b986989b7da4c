// Windowed rate and bandwidth statistics for heslam-spy hz / bw.
#include "tools/spy/arrival_window.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace heslam {

namespace {
constexpr double kNsPerS = 1e9;
}  // namespace

ArrivalWindow::ArrivalWindow(std::size_t window) : window_(window) {
  if (window_ < 2) throw std::runtime_error("--window: must be at least 2 samples");
}

void ArrivalWindow::add(std::int64_t arrival_ns, std::size_t bytes) {
  arrivals_.push_back({arrival_ns, bytes});
  while (arrivals_.size() > window_) arrivals_.pop_front();
}

RateStats ArrivalWindow::rate() const {
  RateStats stats;
  if (arrivals_.size() < 2) return stats;
  stats.periods = arrivals_.size() - 1;
  double sum_s = 0.0;
  double sum_sq_s2 = 0.0;
  stats.min_period_s = INFINITY;
  for (std::size_t i = 1; i < arrivals_.size(); ++i) {
    const double period_s = static_cast<double>(arrivals_[i].arrival_ns - arrivals_[i - 1].arrival_ns) / kNsPerS;
    sum_s += period_s;
    sum_sq_s2 += period_s * period_s;
    stats.min_period_s = std::min(stats.min_period_s, period_s);
    stats.max_period_s = std::max(stats.max_period_s, period_s);
  }
  const double count = static_cast<double>(stats.periods);
  const double mean_s = sum_s / count;
  stats.rate_hz = sum_s > 0.0 ? count / sum_s : 0.0;
  stats.std_period_s = std::sqrt(std::max(0.0, sum_sq_s2 / count - mean_s * mean_s));
  return stats;
}

BandwidthStats ArrivalWindow::bandwidth() const {
  BandwidthStats stats;
  stats.samples = arrivals_.size();
  if (arrivals_.empty()) return stats;
  std::size_t total = 0;
  stats.min_bytes = arrivals_.front().bytes;
  for (const Arrival& arrival : arrivals_) {
    total += arrival.bytes;
    stats.min_bytes = std::min(stats.min_bytes, arrival.bytes);
    stats.max_bytes = std::max(stats.max_bytes, arrival.bytes);
  }
  stats.mean_bytes = static_cast<double>(total) / static_cast<double>(arrivals_.size());
  const double span_s = static_cast<double>(arrivals_.back().arrival_ns - arrivals_.front().arrival_ns) / kNsPerS;
  // The first arrival opens the interval; the bytes that arrived within it are the others'.
  if (span_s > 0.0) stats.bytes_per_s = static_cast<double>(total - arrivals_.front().bytes) / span_s;
  return stats;
}

}  // namespace heslam
