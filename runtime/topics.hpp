// THE table of topics: name (under a namespace, default "heslam"), type and QoS role of every topic.
// Components, tools and tests take topic specs from here, never from string literals.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "runtime/messages.hpp"
#include "runtime/qos.hpp"

namespace heslam::runtime {

inline constexpr std::string_view kDefaultNamespace = "heslam";

// A topic's full DDS name, its message type T and the QoS role its writers and readers use.
template <Message T>
struct TopicSpec {
  std::string name;
  QosRole role;
};

// Relative names (docs/topics.md documents writer and readers of each).
namespace topic_names {
inline constexpr std::string_view kStereo = "camera/stereo";
inline constexpr std::string_view kCalibration = "camera/calibration";
inline constexpr std::string_view kImu = "imu/readings";
inline constexpr std::string_view kImuCalibration = "imu/calibration";
inline constexpr std::string_view kOdometry = "odometry";
inline constexpr std::string_view kKeyframes = "map/keyframes";
inline constexpr std::string_view kKeyframeStates = "map/keyframe_states";
inline constexpr std::string_view kMapPoints = "map/points";
inline constexpr std::string_view kMapperKeyframes = "map/mapper_keyframes";
inline constexpr std::string_view kLoopCorrections = "loop/corrections";
inline constexpr std::string_view kFrameDone = "lockstep/frame_done";
inline constexpr std::string_view kKeyframeDone = "lockstep/keyframe_done";
inline constexpr std::string_view kTurns = "lockstep/turns";
inline constexpr std::string_view kStatus = "system/status";
inline constexpr std::string_view kOccupancyGrid = "map/occupancy_grid";
inline constexpr std::string_view kDenseCloud = "map/dense_cloud";
inline constexpr std::string_view kOccupancySaveRequest = "map/occupancy_save_request";
inline constexpr std::string_view kOccupancySaveReply = "map/occupancy_save_reply";
}  // namespace topic_names

// All topics under one namespace: Topics("robot1").stereo().name == "robot1/camera/stereo".
// Several agents (docs/agents.md): an agent namespace puts the agent's own topics (its source's
// frames, calibration and IMU, its frontend's odometry and FrameDone) under NS/AGENT/, as ROS 2
// namespaces do, while the map topics, corrections, KeyframeDone and status stay shared under NS:
// Topics("heslam", "a").stereo().name == "heslam/a/camera/stereo", .keyframes().name == "heslam/map/keyframes".
class Topics {
 public:
  // Throws std::runtime_error for a namespace (or an agent namespace that is not empty) that is empty
  // or not [A-Za-z0-9_/-] (DDS name rules).
  explicit Topics(std::string_view ns = kDefaultNamespace, std::string_view agent_ns = {});

  const std::string& ns() const { return ns_; }
  const std::string& agent_ns() const { return agent_ns_; }
  std::string full_name(std::string_view relative) const { return ns_ + "/" + std::string(relative); }
  // A topic of one agent: under NS/AGENT/ with an agent namespace, else as full_name.
  std::string agent_name(std::string_view relative) const {
    return agent_ns_.empty() ? full_name(relative) : ns_ + "/" + agent_ns_ + "/" + std::string(relative);
  }

  TopicSpec<msg::StereoFrame> stereo() const { return {agent_name(topic_names::kStereo), QosRole::kImages}; }
  TopicSpec<msg::StereoCalibration> calibration() const {
    return {agent_name(topic_names::kCalibration), QosRole::kCalibration};
  }
  // IMU readings in batches; before a frame with stamp t, a batch with watermark_ns >= t (docs/topics.md).
  TopicSpec<msg::ImuBatch> imu() const { return {agent_name(topic_names::kImu), QosRole::kImu}; }
  TopicSpec<msg::ImuCalibration> imu_calibration() const {
    return {agent_name(topic_names::kImuCalibration), QosRole::kCalibration};
  }
  TopicSpec<msg::Odometry> odometry() const { return {agent_name(topic_names::kOdometry), QosRole::kOdometry}; }
  TopicSpec<msg::Keyframe> keyframes() const { return {full_name(topic_names::kKeyframes), QosRole::kKeyframes}; }
  TopicSpec<msg::KeyframeState> keyframe_states() const {
    return {full_name(topic_names::kKeyframeStates), QosRole::kMapState};
  }
  TopicSpec<msg::MapPointState> map_points() const { return {full_name(topic_names::kMapPoints), QosRole::kMapState}; }
  // Every keyframe of the local mapper's map with its features (the state topics carry none): a
  // frontend restarted without a readable map file of the run (or on another host) rebuilds its map
  // from it.
  TopicSpec<msg::Keyframe> mapper_keyframes() const {
    return {full_name(topic_names::kMapperKeyframes), QosRole::kKeyframes};
  }
  TopicSpec<msg::LoopCorrection> loop_corrections() const {
    return {full_name(topic_names::kLoopCorrections), QosRole::kCorrections};
  }
  TopicSpec<msg::FrameDone> frame_done() const { return {agent_name(topic_names::kFrameDone), QosRole::kLockstep}; }
  TopicSpec<msg::KeyframeDone> keyframe_done() const {
    return {full_name(topic_names::kKeyframeDone), QosRole::kLockstep};
  }
  // Several agents in lockstep (docs/agents.md): each agent's replay announces the stamp of the frame it
  // wants to publish next (FrameDone: stamp_ns, component = its agent namespace; INT64_MAX when done);
  // the frames of all agents then go out in stamp order, one at a time. Shared by the agents.
  TopicSpec<msg::FrameDone> turns() const { return {full_name(topic_names::kTurns), QosRole::kLockstep}; }
  TopicSpec<msg::ComponentStatus> status() const { return {full_name(topic_names::kStatus), QosRole::kStatus}; }
  // heslam-occupancy's 2D grid and dense cloud: latched (the calibration's profile: reliable,
  // transient-local, KEEP_LAST(1)), so a late viewer or bridge gets the newest at once.
  TopicSpec<msg::OccupancyGrid2D> occupancy_grid() const {
    return {full_name(topic_names::kOccupancyGrid), QosRole::kCalibration};
  }
  TopicSpec<msg::DenseCloud> dense_cloud() const {
    return {full_name(topic_names::kDenseCloud), QosRole::kCalibration};
  }
  // heslam-occupancy's map on request (heslam-occupancy-save, as nav2's map_saver asks map_server): the
  // lockstep acknowledgements' profile (reliable, volatile, KEEP_LAST(64)): never lost, never replayed to a
  // late reader; a requester waits for the process's reader to match before it writes.
  TopicSpec<msg::OccupancySaveRequest> occupancy_save_request() const {
    return {full_name(topic_names::kOccupancySaveRequest), QosRole::kLockstep};
  }
  TopicSpec<msg::OccupancySaveReply> occupancy_save_reply() const {
    return {full_name(topic_names::kOccupancySaveReply), QosRole::kLockstep};
  }

 private:
  std::string ns_;
  std::string agent_ns_;
};

// Every topic of the table, for tools that iterate (spy list, docs): relative name, type name, role.
struct TopicEntry {
  std::string_view relative_name;
  std::string_view type_name;
  QosRole role;
};
std::span<const TopicEntry> all_topics();

}  // namespace heslam::runtime
