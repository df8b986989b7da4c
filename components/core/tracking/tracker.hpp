// The stereo frame tracker (ORB-SLAM2 Tracking, stereo, without threads or I/O): one call per frame,
// from stereo features to a pose, a state and, sometimes, a new keyframe with its new map points.
//
// The tracker keeps a Map: alone it fills it itself (keyframes, points, observations, covisibility);
// inside the frontend process the local mapper's state is applied to it (local_map()) and
// TrackerOptions::maintain_map is false. Deterministic: same frames in, same poses out, bit for bit.
//
// With a vocabulary the tracker keeps a keyframe database of its map's keyframes and relocalizes a
// lost frame against the database's candidates anywhere in the map (relocalizer.hpp); without one,
// against the newest keyframes only.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/feature/features.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/place/keyframe_database.hpp"
#include "components/core/place/vocabulary.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/inertial_pose_optimization.hpp"
#include "components/core/tracking/stationary_test.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

// kInertialOnly: vision could not track the frame, the IMU's propagation gave its pose (a frame with a
// pose, not lost: docs/outputs.md); only with a prediction (set_prediction) that allows it.
enum class TrackingState { kNotInitialized, kOk, kLost, kInertialOnly };
const char* to_string(TrackingState state);

// How the frame's pose was first found, before the local map refinement.
enum class TrackingMethod { kNone, kInitialization, kMotionModel, kReferenceKeyframe, kRelocalization, kInertial };
const char* to_string(TrackingMethod method);

// How the pose of a frame after a gap (its seq more than one past the last frame's: frames missed or
// shed in real time) was checked (TrackerOptions, "a frame after a gap"; docs/frontend.md "After a gap").
enum class GapCheck {
  kNoGap,     // the frame follows the last one, or the last one had no pose
  kAccepted,  // after a gap; its first pose was not doubtful
  kChosen,    // its first pose was doubtful: of every start tried, the best was confident and unambiguous
  kRefused,   // ... none was: the frame is lost (or inertial-only with an IMU's pose)
};
const char* to_string(GapCheck check);

struct TrackTimings {
  double initial_pose_ms = 0.0;  // motion model / reference keyframe / relocalization, with its BA
  double local_map_ms = 0.0;     // local map selection, search, BA
  double keyframe_ms = 0.0;      // decision and creation
  double total_ms = 0.0;
};

// Why a frame started a new map (the atlas): the tracker was lost since `lost_since_ns` (the first
// frame without a pose) for `lost_frames` frames, relocalization in every map failed each time.
struct NewMapStart {
  MapId previous_map = kFirstMapId;
  std::int64_t lost_since_ns = 0;
  int lost_frames = 0;
};

struct TrackResult {
  TrackingState state = TrackingState::kNotInitialized;
  TrackingMethod method = TrackingMethod::kNone;
  // Published only when state == kOk or kInertialOnly; otherwise T_wc is the last good pose and must
  // not be used.
  Pose3 T_wc = Pose3::Identity();
  MapId map_id = kFirstMapId;  // the map T_wc is in (the atlas: docs/frontend.md)
  KeyframeId reference_kf = kNoId;
  Pose3 T_ref_c = Pose3::Identity();  // current camera in the reference keyframe's frame
  int tracked_points = 0;             // inlier map points after the local map search
  int tracked_stereo = 0;             // ... of which with a stereo observation
  FrameMotion motion =
      FrameMotion::kMoving;  // still / rotating in place: the stationary test held (part of) the last pose
  std::optional<Keyframe> new_keyframe;
  std::vector<MapPoint> new_points;  // created with new_keyframe
  // Set on the frame that started a new map (its first keyframe is new_keyframe, map_id the new id).
  std::optional<NewMapStart> new_map;
  // The reference keyframe new_keyframe was tracked against (reference_kf is the new keyframe
  // itself then); kNoId for the first keyframe. The mapper moves a keyframe that predates a loop
  // correction with this keyframe.
  KeyframeId new_keyframe_reference = kNoId;
  TrackTimings timings;
  GapCheck gap_check = GapCheck::kNoGap;
  std::uint64_t frames_before_missed = 0;  // seq - last seq - 1: the frames of the gap before this one
  // The velocity and biases of the motion-only optimization with IMU factors (set_inertial_constraint),
  // when it ran for this frame and the frame was tracked.
  std::optional<InertialFrameState> inertial_state;

  bool pose_valid() const { return state == TrackingState::kOk || state == TrackingState::kInertialOnly; }
};

// A map point's tracking counters, saved before a tentative tracking changes them.
struct PointCounters {
  PointId id = kNoId;
  int visible = 0;
  int found = 0;
};

// Where a previous tracker's last frame was: its reference keyframe and its pose in it, and in the
// world (used when that keyframe is not in the map).
struct LastFramePose {
  KeyframeId reference = kNoId;
  Pose3 T_ref_c = Pose3::Identity();
  Pose3 T_wc = Pose3::Identity();
};

class Tracker {
 public:
  // `vocabulary` may be null: no keyframe database, relocalization against the newest keyframes.
  Tracker(const PinholeStereo& camera, const TrackerOptions& options,
          std::shared_ptr<const Vocabulary> vocabulary = nullptr);

  // Throws std::invalid_argument (one line naming the field) on inconsistent features; the tracker's
  // state is unchanged then, so the caller can skip the frame and count it.
  TrackResult track(std::int64_t stamp_ns, std::uint64_t seq, StereoFeatures features);

  // For the next track() call only (an IMU's prediction, components/frontend/inertial_frontend.hpp):
  // `T_wc` replaces the constant-velocity model as the frame's starting pose (also after a frame
  // without velocity, e.g. after an inertial-only frame: the reference keyframe is then searched by
  // projection from it); `fallback` becomes the frame's pose, state kInertialOnly, when vision cannot
  // track it. Without a call, tracking is the stereo-only one, bit for bit.
  void set_prediction(std::optional<Pose3> T_wc, std::optional<Pose3> fallback = std::nullopt) {
    prediction_ = std::move(T_wc);
    inertial_fallback_ = std::move(fallback);
  }

  // For the next track() call only: the local map's motion-only optimization also estimates the frame's
  // velocity and biases with the IMU factor from the previous frame (inertial_pose_optimization.hpp);
  // TrackResult::inertial_state receives them. Without a call, the visual optimization, bit for bit.
  void set_inertial_constraint(std::optional<InertialPoseConstraint> constraint) {
    inertial_constraint_ = std::move(constraint);
  }

  // The atlas's rule from the next frame on (TrackerOptions::new_map_after_ns): a session on a saved map
  // starts its own map sooner at its start than after a loss (docs/local_mapper.md, Multi-session mapping).
  void set_new_map_after_ns(std::int64_t ns) { options_.new_map_after_ns = ns; }

  // Whether the local mapper can take a keyframe now (real-time mode); lockstep keeps it true.
  void set_mapper_idle(bool idle) { mapper_idle_ = idle; }

  // After a restart inside an existing map (a restarted frontend that mirrored the local mapper's
  // map into local_map()): the next frame is relocalized in that map instead of starting a new one,
  // and keyframe / point ids continue after this creator's largest ids in it plus a gap, so they
  // cannot collide with ids the previous process published that the map does not hold yet.
  // Returns false (and changes nothing) when the map holds no keyframe or tracking already started.
  // With `last` (the previous process's last frame, from its journal) the next frame is tracked from
  // that pose against its reference keyframe, as if no restart happened (only the velocity is lost);
  // relocalization is then the fallback, for the frame after it. A reference the map does not hold
  // (its keyframe died with the old process) is replaced by the map's newest keyframe.
  bool resume_in_map(const std::optional<LastFramePose>& last = std::nullopt);
  // Keyframe / point ids this tracker makes from now on have counters above these (never lowers
  // them): a restarted frontend starts in a range of its own (runtime::restart_number()), and one
  // that sees its own tag on an id in the mapper's states skips past it, so no id an earlier process
  // published is made again, whatever files were lost.
  void skip_ids_through(std::uint64_t keyframe_counter, std::uint64_t point_counter);

  // Brings the keyframe database up to the map's keyframes (new ones transformed once, culled ones
  // dropped). The tracker does it itself after each keyframe it creates, before a relocalization and
  // in resume_in_map(); a caller that changed local_map() may call it to spread the cost.
  DatabaseSync sync_place_database();
  // Null without a vocabulary.
  const KeyframeDatabase* place_database() const { return database_ ? &*database_ : nullptr; }
  const std::shared_ptr<const Vocabulary>& vocabulary() const { return vocabulary_; }
  // After a loop correction moved the map under the tracker (the frontend mirrors it): the last
  // frame follows its reference keyframe, keeping its relative pose (ORB-SLAM2's UpdateLastFrame),
  // so the motion model predicts the next frame in the corrected map. No-op without a reference.
  void follow_reference_keyframe();

  Map& local_map() { return map_; }
  const Map& local_map() const { return map_; }
  TrackingState state() const { return state_; }
  // The last frame processed: its pose (T_wc) and matches (outlier flags of its last pose optimization).
  const Frame& last_frame() const { return last_frame_; }
  const PinholeStereo& camera() const { return camera_; }
  const TrackerOptions& options() const { return options_; }

 private:
  // `T_wc_origin`: the first keyframe's pose, the identity for the first map; a new map starts at the
  // last pose the tracker had, so the trajectory goes on from there (docs/frontend.md, Atlas).
  bool initialize(Frame& frame, TrackResult& result, const Pose3& T_wc_origin = Pose3::Identity());
  // The atlas: lost and not relocalized for options_.new_map_after_ns: the frame starts a new map.
  bool new_map_due(std::int64_t stamp_ns) const;
  bool start_new_map(Frame& frame, TrackResult& result);
  bool track_motion_model(Frame& frame, const Pose3& T_wc_start);
  bool track_reference_keyframe(Frame& frame, const Pose3& T_wc_start);
  // The tracking of a frame that had a prediction (set_prediction): motion model search from it,
  // else the reference keyframe's points projected from it.
  bool track_predicted(Frame& frame, const Pose3& T_wc_predicted, TrackResult& result);
  // The first tracking of a frame with a pose before it (motion model, prediction, reference keyframe),
  // the local map included.
  // `start`: the frame's start, for its timings.
  bool track_from_last_frame(Frame& frame, const std::optional<Pose3>& prediction,
                             const InertialPoseConstraint* constraint, TrackResult& result, int& inliers,
                             std::vector<PointCounters>* touched, std::chrono::steady_clock::time_point start);
  // A frame after a gap whose first pose is doubtful: every other start is tried and the best kept when
  // confident and unambiguous (TrackerOptions, "a frame after a gap"). Returns whether the frame has a
  // pose; `inliers` and `result` (method, inertial state) are those of the pose kept.
  // `first_ok`, `inliers`: the first tracking's verdict and inliers; `touched`: the counters it changed.
  bool check_after_gap(Frame& frame, bool first_ok, const std::optional<Pose3>& prediction,
                       const InertialPoseConstraint* constraint, KeyframeId reference_before, TrackResult& result,
                       int& inliers, const std::vector<PointCounters>& touched);
  // With `constraint`, the pose optimization is the inertial one and `state` receives its velocity and biases.
  // `touched`, when given, receives the counters (visible, found) of every point before the search
  // changes them, so that a tentative tracking can be undone.
  bool track_local_map(Frame& frame, int& inliers, const InertialPoseConstraint* constraint,
                       std::optional<InertialFrameState>& state, std::vector<PointCounters>* touched = nullptr);
  void maybe_insert_keyframe(Frame& frame, int inliers, TrackResult& result);
  KeyframeId next_keyframe_id() { return make_id(options_.id_tag, ++keyframe_counter_); }

  PinholeStereo camera_;
  TrackerOptions options_;
  std::shared_ptr<const Vocabulary> vocabulary_;
  std::optional<KeyframeDatabase> database_;  // with a vocabulary: the map's keyframes, by word
  Map map_;
  TrackingState state_ = TrackingState::kNotInitialized;
  Frame last_frame_;
  Pose3 last_T_ref_c_ = Pose3::Identity();  // the last frame in its reference keyframe's frame
  std::optional<Pose3> velocity_;           // T_last_current of the last tracked pair
  KeyframeId reference_kf_ = kNoId;
  MapId active_map_ = options_.first_map_id;   // the map tracked in, and the one new keyframes join
  std::optional<std::int64_t> lost_since_ns_;  // the stamp of the first frame of the current loss
  int lost_frames_ = 0;                        // frames of the current loss
  std::uint64_t keyframe_counter_ = 0;
  std::uint64_t point_counter_ = 1;
  int frames_since_keyframe_ = 0;
  int last_inliers_ = 0;  // local-map inliers of the last tracked frame
  int frames_since_relocalization_ = 1 << 30;
  bool mapper_idle_ = true;
  std::optional<Pose3> prediction_;                            // set_prediction, for the next frame only
  std::optional<Pose3> inertial_fallback_;                     // ... idem
  std::optional<InertialPoseConstraint> inertial_constraint_;  // set_inertial_constraint, idem
};

}  // namespace heslam
