// Which IMU readings go out with which frame (DDS-free, unit-tested). The contract of imu/readings
// (docs/topics.md): before the frame with stamp t, the readings up to and including the first one at
// or after t, with watermark_ns = that reading's stamp (>= t). A reader that holds a watermark >= t
// can thus interpolate at t and knows nothing before it is missing, without waiting on a clock.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "components/core/imu/preintegration.hpp"

namespace heslam {

struct ImuBatchPlan {
  std::vector<ImuSample> samples;  // stamps shifted by the pass offset, strictly increasing over the run
  std::uint64_t first_index = 0;   // index of samples[0] in the published stream
  std::int64_t watermark_ns = 0;   // every reading up to this stamp has now been published
};

class ReplayImu {
 public:
  // recording: the IMU's readings, strictly increasing stamps.
  explicit ReplayImu(std::span<const ImuSample> recording) : recording_(recording) {}

  // Starts a pass (the first, or a --loop pass) whose first frame has the recording stamp
  // first_frame_ns: its first batch starts at the last reading at or before that frame.
  void start_pass(std::int64_t first_frame_ns, std::int64_t pass_offset_ns);

  // The batch to publish before the frame with recording stamp frame_ns. When the recording ended
  // before frame_ns (an IMU that stopped), the batch is empty or short and its watermark frame_ns:
  // the readers learn that no reading is coming, rather than waiting.
  ImuBatchPlan before_frame(std::int64_t frame_ns);

  std::uint64_t published() const { return next_index_; }  // readings, over all passes
  std::int64_t watermark_ns() const { return watermark_ns_; }

 private:
  std::span<const ImuSample> recording_;
  std::size_t next_ = 0;  // next reading of the recording to publish
  std::int64_t pass_offset_ns_ = 0;
  std::uint64_t next_index_ = 0;  // readings published so far (the stream index of the next one)
  std::int64_t last_stamp_ns_ = INT64_MIN;
  std::int64_t watermark_ns_ = INT64_MIN;
};

}  // namespace heslam
