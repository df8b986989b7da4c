// The frontend's per-frame odometry sample: the tracking result, its state and the stage timings.
// The message borrows its sequences from buffers it owns, so it must outlive the write() that sends it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "components/core/tracking/pose_covariance.hpp"
#include "components/core/tracking/tracker.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

struct StageTiming {
  std::string stage;  // at most 31 characters (IDL string<31>); longer names are cut
  double ms = 0.0;
};

class OdometryMessage {
 public:
  // T_wo: odom -> world (the loop corrections followed so far); T_oc = T_wo^-1 T_wc. covariance: of T_wc
  // (pose_covariance.hpp), zeros without one.
  OdometryMessage(std::int64_t stamp_ns, std::uint64_t seq, const TrackResult& result, std::uint32_t keypoints,
                  const std::vector<StageTiming>& timings, const Pose3& T_wo = Pose3::Identity(),
                  const std::optional<PoseCovariance>& covariance = std::nullopt);
  OdometryMessage(const OdometryMessage&) = delete;
  OdometryMessage& operator=(const OdometryMessage&) = delete;
  const msg::Odometry& get() const { return message_; }
  // Inertial tracking: the IMU body's velocity in the world (velocity_valid, v_w).
  void set_velocity(const Eigen::Vector3d& v_w);
  // Inertial tracking, initialized: gravity in the world (gravity_valid, g_w).
  void set_gravity(const Eigen::Vector3d& g_w);

 private:
  std::vector<msg::StageTime> stage_times_;
  msg::Odometry message_{};
};

heslam_msg_TrackingState to_message(TrackingState state);

}  // namespace heslam::messages
