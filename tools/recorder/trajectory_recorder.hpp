// The recorder's bookkeeping without DDS: frames (reference keyframe + relative pose), keyframes and
// their latest poses, turned at the end into the full trajectory as ORB-SLAM2 saves it — each
// frame's pose = final pose of its reference keyframe * T_ref_c — plus the keyframe trajectory and
// the list of frames that have no pose (lost / not initialized), which are never invented.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "tools/eval/trajectory.hpp"

namespace heslam::recorder {

struct RecordedFrame {
  std::int64_t stamp_ns = 0;
  std::uint64_t seq = 0;
  bool tracked = false;  // state OK or INERTIAL_ONLY: the pose fields are meaningful
  std::string state;     // for the lost list: "LOST", "NOT_INITIALIZED"
  KeyframeId reference = kNoId;
  Pose3 T_ref_c = Pose3::Identity();
  Pose3 T_wc = Pose3::Identity();  // as estimated at the time (fallback when the reference is unknown)
  MapId map_id = kFirstMapId;      // Odometry.map_id (fallback when the reference's map is unknown)
  // Inertial tracking: the IMU body's velocity and gravity in the map's world, as estimated at the time.
  std::optional<Eigen::Vector3d> v_w;
  std::optional<Eigen::Vector3d> g_w;
};

// A tracked frame's velocity, in the world of the written trajectory.
struct FrameVelocity {
  std::uint64_t seq = 0;
  double stamp_s = 0.0;
  Eigen::Vector3d v_w = Eigen::Vector3d::Zero();
};

struct LostFrame {
  std::uint64_t seq = 0;
  std::int64_t stamp_ns = 0;
  std::string state;
};

struct RecordedTrajectories {
  eval::Trajectory frames;     // tracked frames in seq order; frame ids = seq
  eval::Trajectory keyframes;  // non-culled keyframes in stamp order; frame ids = their frame seq
  // The atlas: the map of each pose of `frames` / `keyframes`, in their order (a frame's is its
  // reference keyframe's latest map id, which a merge changes).
  std::vector<MapId> frame_maps;
  std::vector<MapId> keyframe_maps;
  bool several_maps() const;
  std::vector<LostFrame> lost;
  int frames_without_reference = 0;  // tracked frames whose keyframe never arrived (odometry pose used)
  // Inertial tracking: the velocities of tracked frames that had one (rotated with their frame's pose
  // when a correction moved it), and the newest frame's gravity in the map's world.
  std::vector<FrameVelocity> velocities;
  std::optional<Eigen::Vector3d> gravity_w;
  // Set by align_to_gravity(): the rotation from the map's world to the gravity-aligned one.
  std::optional<Eigen::Matrix3d> R_gw;
};

// The rotation R_gw of the world whose z is -gravity (up) from the map's world, the smallest that does it:
// the origin and the heading of the map's world are kept. Throws std::invalid_argument on a zero or
// non-finite gravity.
Eigen::Matrix3d gravity_alignment(const Eigen::Vector3d& gravity_w);
// With a gravity, expresses the recording's poses and velocities in the gravity-aligned world (R_gw). The
// poses are already in the written frame's world (express_in_frame with T_x_r, rectified camera -> x): the
// gravity and velocities, of the map's world, are first turned into it by R_x_r; gravity_w then is of it.
void align_to_gravity(RecordedTrajectories& recording, const Pose3& T_x_r = Pose3::Identity());

// What became of the published frames: the run's summary "tracked N/M frames, K lost".
struct FrameAccount {
  std::uint64_t published = 0;  // M: frames published (the replay's count, at least the highest seq + 1)
  std::uint64_t with_pose = 0;  // N: tracked frames, each a pose of the trajectory
  std::uint64_t untracked = 0;  // LOST / NOT_INITIALIZED: in the lost list
  // Seqs below `published` with no odometry at all, as [first, last] ranges: frames the frontend
  // missed (real time) or that never reached the recorder.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> never_received;

  std::uint64_t without_pose() const { return published - with_pose; }  // K
  std::uint64_t never_received_count() const;
  // "3-7, 9, 12-40" (at most max_ranges ranges, then "...").
  std::string never_received_text(std::size_t max_ranges = 8) const;
};

class TrajectoryRecorder {
 public:
  // A frame's odometry. A later sample with the same seq replaces the earlier one.
  void add_frame(const RecordedFrame& frame);
  // A keyframe as created (its initial pose).
  void add_keyframe(KeyframeId id, std::int64_t stamp_ns, std::uint64_t frame_seq, const Pose3& T_wc);
  // The odometry of the frame that created keyframe `id` (its reference then): the keyframe's stamp
  // and frame when its Keyframe sample never arrived (the frontend that wrote it died before this
  // recorder, restarted too, could read it; the restarted frontend publishes its journal's odometry
  // again). A Keyframe sample, earlier or later, wins.
  void add_keyframe_frame(KeyframeId id, std::int64_t stamp_ns, std::uint64_t frame_seq, const Pose3& T_wc);
  // The mapper's latest state of a keyframe. A culled keyframe keeps its pose relative to its parent
  // from then on (ORB-SLAM2's Tcp), so frames referencing it follow the parent.
  void update_keyframe(KeyframeId id, const Pose3& T_wc, KeyframeId parent, bool culled);
  // The keyframe's map (Keyframe.map_id, then the mapper's KeyframeState.map_id: the latest wins).
  void set_keyframe_map(KeyframeId id, MapId map_id);

  // Several agents (docs/agents.md): the keyframe trajectory holds agent `agent`'s keyframes only (the
  // others' states are still kept: a frame of this agent may reference one after a merge). -1: all.
  void set_agent(int agent) { agent_ = agent; }

  RecordedTrajectories build() const;
  // Frames are numbered from 0 by their publisher (StereoFrame.seq); frames_published is its count
  // (0 when unknown: the highest recorded seq + 1 stands in).
  FrameAccount account(std::uint64_t frames_published) const;

  std::size_t frame_count() const { return frames_.size(); }
  std::size_t keyframe_count() const { return keyframes_.size(); }

 private:
  struct KeyframeRecord {
    std::int64_t stamp_ns = 0;
    std::uint64_t frame_seq = 0;
    Pose3 T_wc_initial = Pose3::Identity();
    Pose3 T_wc = Pose3::Identity();
    KeyframeId parent = kNoId;
    bool culled = false;
    std::optional<Pose3> T_parent_kf;   // fixed when culled
    bool from_keyframe_sample = false;  // stamp and frame from the Keyframe sample (else odometry or none)
    std::optional<MapId> map_id;
  };
  // The keyframe's final pose, following culled keyframes up their parents; nullopt when unknown.
  std::optional<Pose3> final_pose(KeyframeId id, int depth = 0) const;
  void cull(KeyframeRecord& record);

  std::map<std::uint64_t, RecordedFrame> frames_;   // by seq
  std::map<KeyframeId, KeyframeRecord> keyframes_;  // by id
  int agent_ = -1;
};

}  // namespace heslam::recorder
