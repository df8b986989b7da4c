// Loop corrections on the wire (loop closer -> local mapper): a core LoopCorrection and back.
// LoopCorrectionMessage borrows its sequences from buffers it owns, so it must outlive the write()
// that sends it.
#pragma once

#include <vector>

#include "components/core/mapping/loop_correction.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

class LoopCorrectionMessage {
 public:
  explicit LoopCorrectionMessage(const LoopCorrection& correction);
  LoopCorrectionMessage(const LoopCorrectionMessage&) = delete;
  LoopCorrectionMessage& operator=(const LoopCorrectionMessage&) = delete;
  const msg::LoopCorrection& get() const { return message_; }

 private:
  std::vector<msg::CorrectedKeyframePose> poses_;
  std::vector<msg::PointMerge> merges_;
  std::vector<msg::CorrectedPointPosition> points_;
  msg::LoopCorrection message_{};
};

// Throws std::runtime_error naming the correction when a pose is not finite or an id is 0.
LoopCorrection to_loop_correction(const msg::LoopCorrection& message);

}  // namespace heslam::messages
