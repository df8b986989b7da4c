// Counters and sliding-window percentiles (nearest rank) per stage.
#include "runtime/stats.hpp"

#include <algorithm>
#include <cmath>

namespace heslam::runtime {
namespace {

double nearest_rank(const std::vector<double>& sorted, double fraction) {
  const auto rank = static_cast<std::size_t>(std::ceil(fraction * static_cast<double>(sorted.size())));
  return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

}  // namespace

void Stats::count(const std::string& counter, uint64_t increment) {
  std::lock_guard lock(mutex_);
  counters_[counter] += increment;
}

void Stats::record_ms(const std::string& stage, double ms) {
  std::lock_guard lock(mutex_);
  Ring& ring = stages_[stage];
  if (ring.values_ms.size() < window_) {
    ring.values_ms.push_back(ms);
  } else {
    ring.values_ms[ring.next] = ms;
  }
  ring.next = (ring.next + 1) % window_;
}

std::map<std::string, uint64_t> Stats::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

std::vector<StageSummary> Stats::stages() const {
  std::vector<StageSummary> out;
  std::lock_guard lock(mutex_);
  for (const auto& [name, ring] : stages_) {
    std::vector<double> sorted = ring.values_ms;
    std::sort(sorted.begin(), sorted.end());
    StageSummary summary;
    summary.name = name;
    summary.count = sorted.size();
    if (!sorted.empty()) {
      summary.p50_ms = nearest_rank(sorted, 0.50);
      summary.p90_ms = nearest_rank(sorted, 0.90);
      summary.p99_ms = nearest_rank(sorted, 0.99);
      summary.max_ms = sorted.back();
    }
    out.push_back(std::move(summary));
  }
  return out;
}

}  // namespace heslam::runtime
