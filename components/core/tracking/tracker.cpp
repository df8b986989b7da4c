// The stereo frame tracker: initialization, motion model / reference keyframe / relocalization,
// local map tracking, keyframe decision.
#include "components/core/tracking/tracker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "components/core/tracking/keyframe_decision.hpp"
#include "components/core/tracking/local_map.hpp"
#include "components/core/tracking/optimize_frame.hpp"
#include "components/core/tracking/projection_search.hpp"
#include "components/core/tracking/relocalizer.hpp"

namespace heslam {
namespace {

// ORB-SLAM2 doubles the motion-model window once before giving up on it.
constexpr float kMotionRetryFactor = 2.f;
// A resumed tracker's ids skip this many past the map's largest: room for every keyframe and point
// the previous process may have published that the mapper had not stored when it died.
constexpr std::uint64_t kResumeIdGap = std::uint64_t{1} << 32;
// For two frames after a relocalization the motion model is not trusted (no velocity yet).
constexpr int kFramesWithoutMotionModelAfterRelocalization = 2;
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

// One line naming the field that is wrong; the frontend skips and counts such frames.
void validate(const StereoFeatures& f) {
  const std::size_t n = f.keypoints.size();
  auto fail = [](const std::string& what) { throw std::invalid_argument("StereoFeatures: " + what); };
  if (f.descriptors.size() != n || f.u_right_px.size() != n || f.depth_m.size() != n) {
    fail("descriptors/u_right_px/depth_m must have one entry per keypoint (" + std::to_string(n) + ")");
  }
  if (f.pyramid.levels < 1 || f.pyramid.scale.size() != static_cast<std::size_t>(f.pyramid.levels) ||
      f.pyramid.inv_sigma2.size() != f.pyramid.scale.size() || f.pyramid.sigma2.size() != f.pyramid.scale.size()) {
    fail("pyramid tables do not match pyramid.levels");
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Keypoint& kp = f.keypoints[i];
    if (kp.octave < 0 || kp.octave >= f.pyramid.levels) fail("keypoint " + std::to_string(i) + " octave out of range");
    if (!std::isfinite(kp.u_px) || !std::isfinite(kp.v_px) || !std::isfinite(f.depth_m[i]) ||
        !std::isfinite(f.u_right_px[i])) {
      fail("keypoint " + std::to_string(i) + " has a non-finite coordinate or depth");
    }
  }
}

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

const char* to_string(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized: return "NOT_INITIALIZED";
    case TrackingState::kOk: return "OK";
    case TrackingState::kLost: return "LOST";
    case TrackingState::kInertialOnly: return "INERTIAL_ONLY";
  }
  return "UNKNOWN";
}

const char* to_string(GapCheck check) {
  switch (check) {
    case GapCheck::kNoGap: return "no_gap";
    case GapCheck::kAccepted: return "accepted";
    case GapCheck::kChosen: return "chosen";
    case GapCheck::kRefused: return "refused";
  }
  return "unknown";
}

const char* to_string(TrackingMethod method) {
  switch (method) {
    case TrackingMethod::kNone: return "none";
    case TrackingMethod::kInitialization: return "initialization";
    case TrackingMethod::kMotionModel: return "motion_model";
    case TrackingMethod::kReferenceKeyframe: return "reference_keyframe";
    case TrackingMethod::kRelocalization: return "relocalization";
    case TrackingMethod::kInertial: return "inertial";
  }
  return "unknown";
}

Tracker::Tracker(const PinholeStereo& camera, const TrackerOptions& options,
                 std::shared_ptr<const Vocabulary> vocabulary)
    : camera_(camera), options_(options), vocabulary_(std::move(vocabulary)) {
  if (vocabulary_ && !vocabulary_->empty()) database_.emplace(*vocabulary_);
}

DatabaseSync Tracker::sync_place_database() { return database_ ? database_->sync(map_) : DatabaseSync{}; }

TrackResult Tracker::track(std::int64_t stamp_ns, std::uint64_t seq, StereoFeatures features) {
  const auto start = std::chrono::steady_clock::now();
  validate(features);
  TrackResult result;
  Frame frame(stamp_ns, seq, std::move(features), camera_);

  if (state_ == TrackingState::kNotInitialized) {
    // Localization only: nothing to track against until a map is loaded (resume_in_map), and no
    // first keyframe may start a new one.
    if (options_.create_keyframes) initialize(frame, result);
    result.timings.total_ms = elapsed_ms(start);
    return result;
  }

  const std::optional<Pose3> prediction = std::exchange(prediction_, std::nullopt);
  const std::optional<Pose3> fallback = std::exchange(inertial_fallback_, std::nullopt);
  const std::optional<InertialPoseConstraint> constraint = std::exchange(inertial_constraint_, std::nullopt);
  const bool last_frame_tracked = state_ == TrackingState::kOk;
  // Tracked from the last frame's pose (a prediction, the motion model, the reference keyframe), or
  // relocalized when the last frame had no pose.
  const bool from_last_frame = last_frame_tracked || (prediction && state_ == TrackingState::kInertialOnly);
  // Frames the tracker never saw lie between the last one and this one (missed or shed in real time;
  // lockstep never has a gap). A restarted tracker's first frame has no last frame to have a gap to.
  const bool after_gap = from_last_frame && last_frame_.size() > 0 && frame.seq > last_frame_.seq + 1;
  if (after_gap) result.frames_before_missed = frame.seq - last_frame_.seq - 1;
  bool ok = false;
  int inliers = 0;
  if (from_last_frame) {
    const KeyframeId reference_before = reference_kf_;
    std::vector<PointCounters> touched;
    ok = track_from_last_frame(frame, prediction, constraint ? &*constraint : nullptr, result, inliers,
                               after_gap ? &touched : nullptr, start);
    if (after_gap) {
      const bool doubtful = !ok || inliers < options_.min_local_map_inliers_after_gap ||
                            inliers < options_.gap_doubt_ratio * last_inliers_;
      if (doubtful) {
        ok = check_after_gap(frame, ok, prediction, constraint ? &*constraint : nullptr, reference_before, result,
                             inliers, touched);
      } else {
        result.gap_check = GapCheck::kAccepted;
      }
    }
  } else {
    frame.T_wc = last_frame_.T_wc;
    sync_place_database();  // keyframes the mapper culled or a loaded map brought since the last sync
    const auto relocalization = relocalize(frame, map_, camera_, options_, place_database());
    if (relocalization) {
      ok = true;
      result.method = TrackingMethod::kRelocalization;
      reference_kf_ = relocalization->keyframe;
      // The atlas: relocalization searches every map; a frame relocalized in another one goes on in it.
      active_map_ = map_.keyframe(reference_kf_)->map_id;
      frames_since_relocalization_ = 0;
    } else if (new_map_due(stamp_ns) && start_new_map(frame, result)) {
      result.timings.total_ms = elapsed_ms(start);
      return result;
    }
    result.timings.initial_pose_ms = elapsed_ms(start);
    if (ok) {
      const auto local_start = std::chrono::steady_clock::now();
      ok = track_local_map(frame, inliers, constraint ? &*constraint : nullptr, result.inertial_state);
      if (!ok) result.inertial_state.reset();
      result.timings.local_map_ms = elapsed_ms(local_start);
    }
  }

  if (ok) {
    state_ = TrackingState::kOk;
    lost_since_ns_.reset();
    lost_frames_ = 0;
    // On the frame's inliers, before keyframe creation adds its new points to the matches.
    std::optional<StationaryTestResult> stationary;
    if (last_frame_tracked) stationary = test_stationary(frame, map_, camera_, options_, last_frame_.T_wc);
    // Counted before keyframe creation adds the new stereo points to the frame's matches.
    for (std::size_t i = 0; i < frame.size(); ++i) {
      if (frame.point_ids[i] != kNoId && frame.features.has_stereo(i)) ++result.tracked_stereo;
    }
    result.tracked_points = inliers;
    last_inliers_ = inliers;
    ++frames_since_keyframe_;
    // The map a tracked frame is in is its reference keyframe's, before a keyframe joins it: a merge may
    // have renumbered that map since the last frame (another agent's keyframe merged it into an older
    // map while this agent made none), and a keyframe made with the old id would start that map again.
    if (const Keyframe* reference = map_.keyframe(reference_kf_)) active_map_ = reference->map_id;
    const auto keyframe_start = std::chrono::steady_clock::now();
    // A pose chosen among several starts is not doubtful, but a keyframe (and its new points) made
    // from it would carry any error into the map: the next frame tracked from it may make one.
    if (result.gap_check != GapCheck::kChosen) maybe_insert_keyframe(frame, inliers, result);
    result.timings.keyframe_ms = elapsed_ms(keyframe_start);
    // A held pose is this frame's output, not an anchor for new map points: a frame that became a
    // keyframe keeps its optimized pose, from which its points were created.
    if (stationary && !result.new_keyframe) {
      result.motion = stationary->motion;
      frame.T_wc = stationary->T_wc;
    }
    if (last_frame_tracked) {
      velocity_ = last_frame_.T_wc.inverse() * frame.T_wc;
    } else {
      velocity_.reset();  // the last frame had no pose: no velocity until two frames in a row are tracked
    }
    result.T_wc = frame.T_wc;
  } else if (fallback) {
    // Vision gave nothing usable: the IMU's pose, from which the next frame searches the map again.
    state_ = TrackingState::kInertialOnly;
    result.method = TrackingMethod::kInertial;
    velocity_.reset();
    frame.clear_matches();
    frame.T_wc = *fallback;
    result.T_wc = frame.T_wc;
  } else {
    state_ = TrackingState::kLost;
    if (!lost_since_ns_) lost_since_ns_ = stamp_ns;
    ++lost_frames_;
    velocity_.reset();
    frame.clear_matches();
    frame.T_wc = last_frame_.T_wc;  // kept only as the relocalization starting guess
    result.T_wc = frame.T_wc;
  }
  ++frames_since_relocalization_;
  result.state = state_;
  result.reference_kf = reference_kf_;
  if (const Keyframe* reference = map_.keyframe(reference_kf_)) {
    result.T_ref_c = reference->T_wc.inverse() * frame.T_wc;
    // The map a tracked frame is in is its reference keyframe's (which a merge may renumber).
    if (result.pose_valid()) active_map_ = reference->map_id;
  }
  result.map_id = active_map_;
  last_T_ref_c_ = result.T_ref_c;
  last_frame_ = std::move(frame);
  result.timings.total_ms = elapsed_ms(start);
  return result;
}

void Tracker::follow_reference_keyframe() {
  const Keyframe* reference = map_.keyframe(reference_kf_);
  if (reference == nullptr || state_ == TrackingState::kNotInitialized) return;
  last_frame_.T_wc = reference->T_wc * last_T_ref_c_;
}

void Tracker::skip_ids_through(std::uint64_t keyframe_counter, std::uint64_t point_counter) {
  keyframe_counter_ = std::max(keyframe_counter_, keyframe_counter);  // pre-incremented: the next is + 1
  point_counter_ = std::max(point_counter_, point_counter + 1);       // the next point's counter itself
}

bool Tracker::resume_in_map(const std::optional<LastFramePose>& last) {
  if (state_ != TrackingState::kNotInitialized || map_.keyframes.empty()) return false;
  const auto counter_of = [](std::uint64_t id) -> std::uint64_t { return id & ((std::uint64_t{1} << 56) - 1); };
  std::uint64_t keyframes = 0;
  std::uint64_t points = 0;
  for (const auto& [id, keyframe] : map_.keyframes) {
    if (creator_of(id) == options_.id_tag) keyframes = std::max(keyframes, counter_of(id));
  }
  for (const auto& [id, point] : map_.points) {
    if (creator_of(id) == options_.id_tag) points = std::max(points, counter_of(id));
  }
  skip_ids_through(keyframes + kResumeIdGap, points + kResumeIdGap);
  reference_kf_ = map_.keyframes.rbegin()->first;
  state_ = TrackingState::kLost;  // the next frame goes to relocalization
  lost_since_ns_.reset();         // ... and a new map may start only after a loss of its own
  lost_frames_ = 0;
  if (last) {
    // The next frame is tracked against the reference keyframe from this pose (track_reference_keyframe),
    // which needs no place recognition: a frame just after a restart is as easy as any other.
    const Keyframe* reference = map_.keyframe(last->reference);
    if (reference != nullptr && !reference->culled) reference_kf_ = last->reference;
    last_frame_.T_wc = reference != nullptr ? reference->T_wc * last->T_ref_c : last->T_wc;
    last_T_ref_c_ = map_.keyframe(reference_kf_)->T_wc.inverse() * last_frame_.T_wc;
    active_map_ = map_.keyframe(reference_kf_)->map_id;
    velocity_.reset();
    state_ = TrackingState::kOk;
  }
  sync_place_database();
  return true;
}

bool Tracker::new_map_due(std::int64_t stamp_ns) const {
  return options_.new_map_after_ns > 0 && options_.create_keyframes && lost_since_ns_ &&
         stamp_ns - *lost_since_ns_ >= options_.new_map_after_ns;
}

bool Tracker::start_new_map(Frame& frame, TrackResult& result) {
  // The next id after every map this tracker knows (its own and the mirror's): a restarted frontend
  // that mirrors the mapper's map continues the numbering.
  // Only this agent's maps count (ids.hpp): after a merge into another agent's map, active_map_ is that
  // agent's, and its next map id is not ours to take.
  const auto own = [this](MapId map_id) { return agent_of_map(map_id) == agent_of_map(options_.first_map_id); };
  MapId newest = own(active_map_) ? active_map_ : options_.first_map_id;
  for (const auto& [id, keyframe] : map_.keyframes) {
    if (own(keyframe.map_id)) newest = std::max(newest, keyframe.map_id);
  }
  const NewMapStart why{active_map_, *lost_since_ns_, lost_frames_};
  const MapId previous = active_map_;
  const KeyframeId previous_reference = reference_kf_;
  active_map_ = newest + 1;
  // Its origin: the last pose the tracker had (the last tracked frame's, or the IMU's), so the
  // trajectory and the odometry go on from there instead of jumping to the identity.
  if (!initialize(frame, result, last_frame_.T_wc)) {
    active_map_ = previous;
    reference_kf_ = previous_reference;
    return false;
  }
  result.new_map = why;
  last_T_ref_c_ = Pose3::Identity();
  lost_since_ns_.reset();
  lost_frames_ = 0;
  velocity_.reset();
  frames_since_relocalization_ = 1 << 30;
  return true;
}

bool Tracker::initialize(Frame& frame, TrackResult& result, const Pose3& T_wc_origin) {
  int stereo = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) stereo += frame.features.has_stereo(i) ? 1 : 0;
  result.state = TrackingState::kNotInitialized;
  if (static_cast<int>(frame.size()) < options_.min_features_to_initialize ||
      stereo < options_.min_stereo_points_to_initialize) {
    return false;
  }

  // The first keyframe is the world origin (of its map) and gets a point for every stereo feature, near
  // or far.
  frame.T_wc = T_wc_origin;
  TrackerOptions all_points = options_;
  all_points.new_keyframe_min_points = std::numeric_limits<int>::max();
  KeyframeCandidate candidate =
      make_keyframe(frame, camera_, map_, next_keyframe_id(), point_counter_, all_points, active_map_);
  insert_keyframe(map_, candidate, camera_, options_);
  frame.point_ids = candidate.keyframe.point_ids;
  sync_place_database();

  state_ = TrackingState::kOk;
  reference_kf_ = candidate.keyframe.id;
  frames_since_keyframe_ = 0;
  result.state = state_;
  result.map_id = active_map_;
  result.method = TrackingMethod::kInitialization;
  result.T_wc = frame.T_wc;
  result.reference_kf = reference_kf_;
  result.tracked_points = static_cast<int>(candidate.new_points.size());
  result.tracked_stereo = result.tracked_points;
  result.new_keyframe = std::move(candidate.keyframe);
  result.new_points = std::move(candidate.new_points);
  last_frame_ = std::move(frame);
  return true;
}

bool Tracker::track_predicted(Frame& frame, const Pose3& T_wc_predicted, TrackResult& result) {
  // The last frame's matches (none after an inertial-only frame) guide the search as in the motion
  // model; without enough, the reference keyframe's points are projected from the prediction.
  if (state_ == TrackingState::kOk && track_motion_model(frame, T_wc_predicted)) {
    result.method = TrackingMethod::kMotionModel;
    return true;
  }
  if (track_reference_keyframe(frame, T_wc_predicted)) {
    result.method = TrackingMethod::kReferenceKeyframe;
    return true;
  }
  return false;
}

bool Tracker::track_from_last_frame(Frame& frame, const std::optional<Pose3>& prediction,
                                    const InertialPoseConstraint* constraint, TrackResult& result, int& inliers,
                                    std::vector<PointCounters>* touched, std::chrono::steady_clock::time_point start) {
  bool ok = false;
  if (prediction) {
    ok = track_predicted(frame, *prediction, result);
  } else {
    if (velocity_ && frames_since_relocalization_ >= kFramesWithoutMotionModelAfterRelocalization) {
      ok = track_motion_model(frame, last_frame_.T_wc * *velocity_);
      if (ok) result.method = TrackingMethod::kMotionModel;
    }
    if (!ok) {
      ok = track_reference_keyframe(frame, last_frame_.T_wc);
      if (ok) result.method = TrackingMethod::kReferenceKeyframe;
    }
  }
  result.timings.initial_pose_ms = elapsed_ms(start);
  inliers = 0;
  if (ok) {
    const auto local_start = std::chrono::steady_clock::now();
    ok = track_local_map(frame, inliers, constraint, result.inertial_state, touched);
    if (!ok) result.inertial_state.reset();
    result.timings.local_map_ms = elapsed_ms(local_start);
  }
  return ok;
}

bool Tracker::check_after_gap(Frame& frame, bool first_ok, const std::optional<Pose3>& prediction,
                              const InertialPoseConstraint* constraint, KeyframeId reference_before,
                              TrackResult& result, int& inliers, const std::vector<PointCounters>& touched) {
  // The first tracking is undone (the map points' counters, the reference keyframe); each start below
  // runs from this same state, so the one kept can be run again for real with the same result.
  for (auto it = touched.rbegin(); it != touched.rend(); ++it) {
    if (MapPoint* point = map_.point(it->id)) {
      point->visible = it->visible;
      point->found = it->found;
    }
  }
  reference_kf_ = reference_before;
  std::vector<std::pair<int, int>> counters;
  counters.reserve(map_.points.size());
  for (const auto& [id, point] : map_.points) counters.emplace_back(point.visible, point.found);
  const int relocalization_count = frames_since_relocalization_;
  const MapId map_before = active_map_;
  const auto restore = [&] {
    auto saved = counters.begin();
    for (auto& [id, point] : map_.points) {
      point.visible = saved->first;
      point.found = saved->second;
      ++saved;
    }
    reference_kf_ = reference_before;
    frames_since_relocalization_ = relocalization_count;
    active_map_ = map_before;
  };

  // The starts: the first one (the prediction, else the motion model), then the one-frame motion model
  // when a prediction replaced it, the last pose (the camera did not move), and relocalization, which
  // owes nothing to any pose before the gap.
  enum class Start { kFirst, kMotionModel, kLastPose, kRelocalization };
  const auto run = [&](Start how, TrackResult& out, int& found) {
    out.method = TrackingMethod::kNone;
    out.inertial_state.reset();
    found = 0;
    bool ok = false;
    switch (how) {
      case Start::kFirst:
        return track_from_last_frame(frame, prediction, constraint, out, found, nullptr,
                                     std::chrono::steady_clock::now());
      case Start::kMotionModel:
        return track_from_last_frame(frame, std::nullopt, constraint, out, found, nullptr,
                                     std::chrono::steady_clock::now());
      case Start::kLastPose:
        return track_from_last_frame(frame, last_frame_.T_wc, constraint, out, found, nullptr,
                                     std::chrono::steady_clock::now());
      case Start::kRelocalization: {
        frame.T_wc = last_frame_.T_wc;
        sync_place_database();
        const auto relocalization = relocalize(frame, map_, camera_, options_, place_database());
        if (!relocalization) return false;
        out.method = TrackingMethod::kRelocalization;
        reference_kf_ = relocalization->keyframe;
        active_map_ = map_.keyframe(reference_kf_)->map_id;
        frames_since_relocalization_ = 0;
        ok = track_local_map(frame, found, constraint, out.inertial_state);
        if (!ok) out.inertial_state.reset();
        return ok;
      }
    }
    return ok;
  };

  struct Candidate {
    Start start;
    bool ok = false;
    int inliers = 0;
    Pose3 T_wc = Pose3::Identity();
  };
  std::vector<Candidate> candidates;
  candidates.push_back({Start::kFirst, first_ok, inliers, frame.T_wc});
  std::vector<Start> others;
  if (prediction) others.push_back(Start::kMotionModel);
  others.push_back(Start::kLastPose);
  others.push_back(Start::kRelocalization);
  for (const Start how : others) {
    TrackResult scratch;
    int found = 0;
    const bool ok = run(how, scratch, found);
    candidates.push_back({how, ok, found, frame.T_wc});
    restore();
  }

  const Candidate* best = nullptr;
  for (const Candidate& candidate : candidates) {
    if (candidate.ok && (best == nullptr || candidate.inliers > best->inliers)) best = &candidate;
  }
  bool accepted = best != nullptr && best->inliers >= options_.min_local_map_inliers_after_gap;
  if (accepted) {
    const double max_distance_m = options_.gap_agreement_baselines * camera_.baseline_m;
    const double max_angle_rad = options_.gap_agreement_deg * kDegToRad;
    for (const Candidate& other : candidates) {
      if (!other.ok || &other == best) continue;
      const Pose3 difference = best->T_wc.inverse() * other.T_wc;
      const bool apart = difference.translation().norm() > max_distance_m ||
                         Eigen::AngleAxisd(difference.rotation()).angle() > max_angle_rad;
      if (apart && other.inliers >= options_.gap_ambiguity_ratio * best->inliers) accepted = false;
    }
  }
  if (!accepted) {
    frame.clear_matches();
    result.inertial_state.reset();
    result.method = TrackingMethod::kNone;
    result.gap_check = GapCheck::kRefused;
    inliers = 0;
    return false;
  }
  // The pose kept, tracked again for real (the same result: every step is deterministic).
  const auto timings = result.timings;
  const bool ok = run(best->start, result, inliers);
  result.timings = timings;
  result.gap_check = GapCheck::kChosen;
  return ok;
}

bool Tracker::track_motion_model(Frame& frame, const Pose3& T_wc_start) {
  frame.T_wc = T_wc_start;
  frame.clear_matches();
  int matches = search_from_last_frame(frame, last_frame_, map_, camera_, options_.motion_search_radius_px, options_);
  if (matches < options_.min_motion_matches) {
    frame.clear_matches();
    matches = search_from_last_frame(frame, last_frame_, map_, camera_,
                                     kMotionRetryFactor * options_.motion_search_radius_px, options_);
  }
  if (matches < options_.min_motion_matches) {
    frame.clear_matches();
    return false;
  }
  optimize_frame_pose(frame, map_, camera_, options_);
  return frame.discard_outliers() >= options_.min_pose_inliers;
}

bool Tracker::track_reference_keyframe(Frame& frame, const Pose3& T_wc_start) {
  const Keyframe* reference = map_.keyframe(reference_kf_);
  if (reference == nullptr) return false;
  frame.T_wc = T_wc_start;
  frame.clear_matches();
  int matches = search_keyframe_by_projection(frame, *reference, map_, camera_, options_.reference_search_radius_px,
                                              options_.reference_ratio, options_);
  if (matches < options_.min_reference_matches) {
    frame.clear_matches();
    matches = search_keyframe_brute_force(frame, *reference, map_, options_.reference_ratio, options_);
  }
  if (matches < options_.min_reference_matches) {
    frame.clear_matches();
    return false;
  }
  optimize_frame_pose(frame, map_, camera_, options_);
  return frame.discard_outliers() >= options_.min_pose_inliers;
}

bool Tracker::track_local_map(Frame& frame, int& inliers, const InertialPoseConstraint* constraint,
                              std::optional<InertialFrameState>& state, std::vector<PointCounters>* touched) {
  const LocalMapSelection local = select_local_map(frame, map_, options_);
  if (local.reference != kNoId) reference_kf_ = local.reference;
  if (touched != nullptr) {
    const auto save = [&](PointId id) {
      if (const MapPoint* point = map_.point(id)) touched->push_back({id, point->visible, point->found});
    };
    for (const PointId id : frame.point_ids) {
      if (id != kNoId) save(id);
    }
    for (const PointId id : local.points) save(id);
  }
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (MapPoint* point = map_.point(frame.point_ids[i])) ++point->visible;
  }
  const bool recently_relocalized = frames_since_relocalization_ < kFramesWithoutMotionModelAfterRelocalization;
  const float radius =
      recently_relocalized ? options_.local_search_radius_relocalized_px : options_.local_search_radius_px;
  search_local_points(frame, local.points, map_, camera_, radius, options_);
  if (constraint != nullptr) {
    optimize_frame_pose_inertial(frame, map_, camera_, options_, *constraint, state);
  } else {
    optimize_frame_pose(frame, map_, camera_, options_);
  }
  inliers = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] == kNoId || frame.outlier[i]) continue;
    if (MapPoint* point = map_.point(frame.point_ids[i])) {
      ++point->found;
      ++inliers;
    }
  }
  frame.discard_outliers();
  const int needed = frames_since_relocalization_ < options_.max_frames_between_keyframes
                         ? options_.min_local_map_inliers_after_relocalization
                         : options_.min_local_map_inliers;
  return inliers >= needed;
}

void Tracker::maybe_insert_keyframe(Frame& frame, int inliers, TrackResult& result) {
  if (!options_.create_keyframes) return;  // localization only
  const Keyframe* reference = map_.keyframe(reference_kf_);
  if (reference == nullptr) return;
  KeyframeDecisionInput input;
  input.frames_since_keyframe = frames_since_keyframe_;
  input.frames_since_relocalization = frames_since_relocalization_;
  input.tracked_inliers = inliers;
  input.keyframes_in_map = static_cast<int>(map_.keyframes.size());
  const int min_observations = reference_min_observations(input.keyframes_in_map);
  const ObservationCount unit = options_.maintain_map ? ObservationCount::keyframes : ObservationCount::weighted;
  input.reference_tracked_points = count_reference_points(*reference, map_, min_observations, unit);
  if (options_.reference_near_clip_weight != 1.0) {
    input.reference_points_near_clip = count_reference_points_near_clip(*reference, map_, min_observations, unit);
    input.tracked_inliers_near_clip = count_tracked_near_clip(frame);
  }
  input.mapper_idle = mapper_idle_ || options_.assume_mapper_idle;
  input.revisit_covered = revisit_covered(frame, map_, camera_, options_);
  if (!decide_keyframe(frame, camera_, input, options_).insert) return;

  KeyframeCandidate candidate =
      make_keyframe(frame, camera_, map_, next_keyframe_id(), point_counter_, options_, active_map_);
  insert_keyframe(map_, candidate, camera_, options_);
  frame.point_ids = candidate.keyframe.point_ids;  // the next frame tracks the new points too
  sync_place_database();                           // the new keyframe, transformed once
  result.new_keyframe_reference = reference_kf_;
  reference_kf_ = candidate.keyframe.id;
  frames_since_keyframe_ = 0;
  result.new_keyframe = std::move(candidate.keyframe);
  result.new_points = std::move(candidate.new_points);
}

}  // namespace heslam
