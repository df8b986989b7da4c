// TrackResult -> msg::Odometry (see odometry.hpp).
#include "components/messages/odometry.hpp"

#include <algorithm>
#include <cstring>

#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::messages {
namespace {

// IDL string<31>: 31 characters and the terminating zero.
constexpr std::size_t kStageNameCapacity = sizeof(msg::StageTime{}.stage);
// Every topic type carries at most this many stage times (IDL sequence<StageTime, 16>).
constexpr std::size_t kMaxStageTimes = 16;

}  // namespace

heslam_msg_TrackingState to_message(TrackingState state) {
  switch (state) {
    case TrackingState::kOk: return heslam_msg_TRACKING_OK;
    case TrackingState::kLost: return heslam_msg_TRACKING_LOST;
    case TrackingState::kInertialOnly: return heslam_msg_TRACKING_INERTIAL_ONLY;
    case TrackingState::kNotInitialized: break;
  }
  return heslam_msg_TRACKING_NOT_INITIALIZED;
}

OdometryMessage::OdometryMessage(std::int64_t stamp_ns, std::uint64_t seq, const TrackResult& result,
                                 std::uint32_t keypoints, const std::vector<StageTiming>& timings, const Pose3& T_wo,
                                 const std::optional<PoseCovariance>& covariance) {
  message_.stamp_ns = stamp_ns;
  message_.seq = seq;
  message_.state = to_message(result.state);
  message_.map_id = result.map_id;
  // Never a garbage pose: a frame that is not tracked carries the identity, and its state says so.
  message_.T_wc = to_message(result.pose_valid() ? result.T_wc : Pose3::Identity());
  message_.reference_keyframe_id = result.pose_valid() ? result.reference_kf : kNoId;
  message_.T_ref_c = to_message(result.pose_valid() ? result.T_ref_c : Pose3::Identity());
  message_.T_oc = to_message(result.pose_valid() ? Pose3(T_wo.inverse() * result.T_wc) : Pose3::Identity());
  if (result.pose_valid() && covariance) {
    std::size_t k = 0;
    for (int row = 0; row < 6; ++row) {
      for (int col = row; col < 6; ++col) message_.T_wc_covariance[k++] = covariance->covariance_wc(row, col);
    }
  }
  message_.keypoints = keypoints;
  message_.tracked_points = static_cast<std::uint32_t>(std::max(0, result.tracked_points));
  message_.keyframe_created = result.new_keyframe.has_value();
  const std::size_t count = std::min(timings.size(), kMaxStageTimes);
  stage_times_.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    msg::StageTime& entry = stage_times_[i];
    std::memset(entry.stage, 0, kStageNameCapacity);
    std::memcpy(entry.stage, timings[i].stage.data(), std::min(timings[i].stage.size(), kStageNameCapacity - 1));
    entry.ms = static_cast<float>(timings[i].ms);
  }
  runtime::borrow(message_.stage_times, stage_times_);
}

void OdometryMessage::set_velocity(const Eigen::Vector3d& v_w) {
  message_.velocity_valid = true;
  for (int i = 0; i < 3; ++i) message_.v_w[i] = v_w[i];
}

void OdometryMessage::set_gravity(const Eigen::Vector3d& g_w) {
  message_.gravity_valid = true;
  for (int i = 0; i < 3; ++i) message_.g_w[i] = g_w[i];
}

}  // namespace heslam::messages
