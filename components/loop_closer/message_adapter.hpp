// The ONE place where a loop closer converts its core LoopCorrection into the IDL sample. The message
// borrows its sequences from buffers it owns, so it must outlive the write() that sends it.
#pragma once

#include <vector>

#include "components/core/mapping/loop_correction.hpp"
#include "runtime/messages.hpp"

namespace heslam::loop_closer {

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

}  // namespace heslam::loop_closer
