// Rebuilding the trajectory from reference keyframes at the end of a run.
#include "tools/recorder/trajectory_recorder.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace heslam::recorder {
namespace {

// A parent chain longer than this is a cycle in corrupt state, not a real spanning tree walk.
constexpr int kMaxParentDepth = 100000;
constexpr double kNsPerSecond = 1e9;

bool bit_equal(const Pose3& a, const Pose3& b) { return a.matrix() == b.matrix(); }

}  // namespace

void TrajectoryRecorder::add_frame(const RecordedFrame& frame) { frames_[frame.seq] = frame; }

void TrajectoryRecorder::add_keyframe(KeyframeId id, std::int64_t stamp_ns, std::uint64_t frame_seq,
                                      const Pose3& T_wc) {
  auto [it, inserted] = keyframes_.try_emplace(id);
  KeyframeRecord& record = it->second;
  record.stamp_ns = stamp_ns;
  record.frame_seq = frame_seq;
  record.T_wc_initial = T_wc;
  record.from_keyframe_sample = true;
  if (inserted) record.T_wc = T_wc;  // a state that arrived first already holds the refined pose
}

void TrajectoryRecorder::add_keyframe_frame(KeyframeId id, std::int64_t stamp_ns, std::uint64_t frame_seq,
                                            const Pose3& T_wc) {
  auto [it, inserted] = keyframes_.try_emplace(id);
  KeyframeRecord& record = it->second;
  if (record.from_keyframe_sample) return;
  record.stamp_ns = stamp_ns;
  record.frame_seq = frame_seq;
  if (inserted) record.T_wc_initial = record.T_wc = T_wc;
}

void TrajectoryRecorder::update_keyframe(KeyframeId id, const Pose3& T_wc, KeyframeId parent, bool culled) {
  auto [it, inserted] = keyframes_.try_emplace(id);
  KeyframeRecord& record = it->second;
  if (inserted) record.T_wc_initial = T_wc;
  if (record.culled) return;  // frozen relative to its parent
  record.T_wc = T_wc;
  record.parent = parent;
  if (culled) cull(record);
}

void TrajectoryRecorder::set_keyframe_map(KeyframeId id, MapId map_id) { keyframes_[id].map_id = map_id; }

bool RecordedTrajectories::several_maps() const {
  const auto other = [](MapId id) { return id != kFirstMapId; };
  return std::any_of(frame_maps.begin(), frame_maps.end(), other) ||
         std::any_of(keyframe_maps.begin(), keyframe_maps.end(), other);
}

void TrajectoryRecorder::cull(KeyframeRecord& record) {
  record.culled = true;
  auto parent = keyframes_.find(record.parent);
  if (record.parent != kNoId && parent != keyframes_.end()) {
    record.T_parent_kf = parent->second.T_wc.inverse() * record.T_wc;
  }
}

std::optional<Pose3> TrajectoryRecorder::final_pose(KeyframeId id, int depth) const {
  auto it = keyframes_.find(id);
  if (it == keyframes_.end() || depth > kMaxParentDepth) return std::nullopt;
  const KeyframeRecord& record = it->second;
  if (!record.culled || !record.T_parent_kf) return record.T_wc;
  const std::optional<Pose3> parent = final_pose(record.parent, depth + 1);
  if (!parent) return record.T_wc;
  return *parent * *record.T_parent_kf;
}

RecordedTrajectories TrajectoryRecorder::build() const {
  RecordedTrajectories out;
  out.frames.name = "frames";
  out.keyframes.name = "keyframes";
  for (const auto& [seq, frame] : frames_) {
    if (!frame.tracked) {
      out.lost.push_back({seq, frame.stamp_ns, frame.state});
      continue;
    }
    Pose3 T_wc = frame.T_wc;
    auto keyframe = keyframes_.find(frame.reference);
    const std::optional<Pose3> reference = final_pose(frame.reference);
    if (!reference) {
      ++out.frames_without_reference;
    } else if (keyframe->second.culled || !bit_equal(*reference, keyframe->second.T_wc_initial)) {
      // The reference moved (refined, corrected, culled): re-express the frame with its final pose.
      // An unmoved reference keeps the tracker's own pose, bit for bit (same value up to rounding).
      T_wc = *reference * frame.T_ref_c;
    }
    const double stamp_s = static_cast<double>(frame.stamp_ns) / kNsPerSecond;
    out.frames.push_back(T_wc, static_cast<std::int64_t>(seq), stamp_s);
    out.frame_maps.push_back(keyframe != keyframes_.end() && keyframe->second.map_id ? *keyframe->second.map_id
                                                                                     : frame.map_id);
    // The velocity turns with the frame's pose when a correction moved it.
    if (frame.v_w)
      out.velocities.push_back({seq, stamp_s, T_wc.linear() * frame.T_wc.linear().transpose() * *frame.v_w});
    if (frame.g_w) out.gravity_w = frame.g_w;  // the newest estimate
  }
  std::vector<std::pair<std::int64_t, KeyframeId>> by_stamp;
  for (const auto& [id, record] : keyframes_) {
    if (!record.culled && (agent_ < 0 || agent_of(id) == agent_)) by_stamp.emplace_back(record.stamp_ns, id);
  }
  std::sort(by_stamp.begin(), by_stamp.end());
  for (const auto& [stamp_ns, id] : by_stamp) {
    const KeyframeRecord& record = keyframes_.at(id);
    out.keyframes.push_back(record.T_wc, static_cast<std::int64_t>(record.frame_seq),
                            static_cast<double>(stamp_ns) / kNsPerSecond);
    out.keyframe_maps.push_back(record.map_id.value_or(kFirstMapId));
  }
  return out;
}

std::uint64_t FrameAccount::never_received_count() const {
  std::uint64_t count = 0;
  for (const auto& [first, last] : never_received) count += last - first + 1;
  return count;
}

std::string FrameAccount::never_received_text(std::size_t max_ranges) const {
  std::ostringstream text;
  for (std::size_t i = 0; i < never_received.size(); ++i) {
    if (i == max_ranges) {
      text << ", ...";
      break;
    }
    const auto& [first, last] = never_received[i];
    text << (i == 0 ? "" : ", ") << first;
    if (last > first) text << "-" << last;
  }
  return text.str();
}

FrameAccount TrajectoryRecorder::account(std::uint64_t frames_published) const {
  FrameAccount account;
  const std::uint64_t highest_plus_one = frames_.empty() ? 0 : frames_.rbegin()->first + 1;
  account.published = std::max(frames_published, highest_plus_one);
  std::uint64_t next = 0;  // the first seq not yet accounted for
  for (const auto& [seq, frame] : frames_) {
    if (seq > next) account.never_received.emplace_back(next, seq - 1);
    next = seq + 1;
    ++(frame.tracked ? account.with_pose : account.untracked);
  }
  if (account.published > next) account.never_received.emplace_back(next, account.published - 1);
  return account;
}

Eigen::Matrix3d gravity_alignment(const Eigen::Vector3d& gravity_w) {
  if (!gravity_w.allFinite() || !(gravity_w.norm() > 0.0)) {
    throw std::invalid_argument("gravity_alignment: gravity must be finite and non-zero");
  }
  // The smallest rotation taking gravity's direction to -z: about the horizontal axis g x -z, so that
  // no rotation about the vertical is added (the map's heading kept).
  return Eigen::Quaterniond::FromTwoVectors(gravity_w.normalized(), -Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

void align_to_gravity(RecordedTrajectories& recording, const Pose3& T_x_r) {
  const Eigen::Matrix3d R_x_r = T_x_r.linear();
  for (FrameVelocity& velocity : recording.velocities) velocity.v_w = R_x_r * velocity.v_w;
  if (!recording.gravity_w) return;
  recording.gravity_w = R_x_r * *recording.gravity_w;
  const Eigen::Matrix3d R_gw = gravity_alignment(*recording.gravity_w);
  Pose3 T_gw = Pose3::Identity();
  T_gw.linear() = R_gw;
  for (eval::Trajectory* trajectory : {&recording.frames, &recording.keyframes}) {
    for (Pose3& pose : trajectory->poses_wc) pose = T_gw * pose;
  }
  for (FrameVelocity& velocity : recording.velocities) velocity.v_w = R_gw * velocity.v_w;
  recording.R_gw = R_gw;
}

}  // namespace heslam::recorder
