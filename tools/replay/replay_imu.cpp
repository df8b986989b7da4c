// The replay's IMU batches (replay_imu.hpp).
#include "tools/replay/replay_imu.hpp"

#include <algorithm>

namespace heslam {

void ReplayImu::start_pass(std::int64_t first_frame_ns, std::int64_t pass_offset_ns) {
  pass_offset_ns_ = pass_offset_ns;
  const auto after =
      std::upper_bound(recording_.begin(), recording_.end(), first_frame_ns,
                       [](std::int64_t stamp, const ImuSample& sample) { return stamp < sample.stamp_ns; });
  next_ = static_cast<std::size_t>(after - recording_.begin());
  if (next_ > 0) --next_;  // the last reading at or before the first frame
}

ImuBatchPlan ReplayImu::before_frame(std::int64_t frame_ns) {
  ImuBatchPlan plan;
  plan.first_index = next_index_;
  while (next_ < recording_.size()) {
    ImuSample sample = recording_[next_];
    ++next_;
    const bool reaches_frame = sample.stamp_ns >= frame_ns;
    sample.stamp_ns += pass_offset_ns_;
    // A --loop pass starts again before the last pass's readings ended: those stamps were covered.
    if (sample.stamp_ns > last_stamp_ns_) {
      plan.samples.push_back(sample);
      last_stamp_ns_ = sample.stamp_ns;
    }
    if (reaches_frame) break;
  }
  next_index_ += plan.samples.size();
  watermark_ns_ = std::max({watermark_ns_, last_stamp_ns_, frame_ns + pass_offset_ns_});
  plan.watermark_ns = watermark_ns_;
  return plan;
}

}  // namespace heslam
