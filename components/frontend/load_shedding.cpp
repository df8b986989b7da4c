// Load shedding of a real-time frontend: the options, the shedding rule and the prediction over gaps.
#include "components/frontend/load_shedding.hpp"

#include <stdexcept>

#include <Eigen/Geometry>

namespace heslam::frontend {
namespace {

// A delay or an age beyond a minute is a typo, not a setting.
constexpr double kMaxMs = 60'000.0;

}  // namespace

LoadSheddingOptions LoadSheddingOptions::from_config(const runtime::Config& config, bool lockstep) {
  LoadSheddingOptions options;
  options.shed_after_ms = config.get_double("realtime.shed_frames_after_ms", options.shed_after_ms, 0.0, kMaxMs);
  options.predict_over_gaps = config.get_bool("realtime.predict_over_gaps", options.predict_over_gaps);
  options.frame_delay_ms = config.get_double("debug.frame_delay_ms", options.frame_delay_ms, 0.0, kMaxMs);
  if (lockstep && options.shed_after_ms > 0.0) {
    throw std::runtime_error(
        "realtime.shed_frames_after_ms: a lockstep frontend (lockstep.wait_for_mapper: true) is never behind its "
        "source; expected 0 (shedding is for real-time configs)");
  }
  return options;
}

bool shed_frame(const LoadSheddingOptions& options, double age_ms, bool newer_frame_waiting) {
  return options.shed_after_ms > 0.0 && newer_frame_waiting && age_ms >= options.shed_after_ms;
}

void GapPrediction::record(std::uint64_t seq, bool tracked, const Pose3& T_wc) {
  if (tracked && last_T_wc_ && last_seq_ && seq > *last_seq_) {
    motion_ = last_T_wc_->inverse() * T_wc;
    motion_gap_ = seq - *last_seq_;
  } else {
    motion_.reset();
  }
  last_seq_ = seq;
  if (tracked) {
    last_T_wc_ = T_wc;
  } else {
    last_T_wc_.reset();
  }
}

std::optional<Pose3> GapPrediction::predict(std::uint64_t seq, const Pose3& T_wc_last) const {
  if (!motion_ || !last_seq_ || seq <= *last_seq_ || motion_gap_ == 0) return std::nullopt;
  const std::uint64_t gap = seq - *last_seq_;
  if (gap == motion_gap_) return std::nullopt;
  return T_wc_last * scale_motion(*motion_, static_cast<double>(gap) / static_cast<double>(motion_gap_));
}

Pose3 scale_motion(const Pose3& motion, double factor) {
  const Eigen::AngleAxisd rotation(motion.rotation());
  Pose3 scaled = Pose3::Identity();
  scaled.linear() = Eigen::AngleAxisd(rotation.angle() * factor, rotation.axis()).toRotationMatrix();
  scaled.translation() = motion.translation() * factor;
  return scaled;
}

}  // namespace heslam::frontend
