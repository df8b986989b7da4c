// The viewer's map and frame state (see viewer_model.hpp).
#include "tools/viewer/viewer_model.hpp"

#include <algorithm>
#include <string>

#include "components/messages/camera.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::viewer {
namespace {

// Frames kept for the 2D view: in lockstep a frame's odometry arrives a frame time after the frame,
// so a few are enough to pair the newest odometry with its image.
constexpr std::size_t kFrameRing = 8;
// Keyframes whose points are projected into a non-keyframe frame: the reference keyframe and this
// many of its best covisible neighbours (the tracker's local map, roughly).
constexpr std::size_t kProjectedNeighbours = 10;

bool is_tracking(TrackingStatus status) {
  return status == TrackingStatus::kTracking || status == TrackingStatus::kRelocalized;
}

}  // namespace

const char* to_string(TrackingStatus status) {
  switch (status) {
    case TrackingStatus::kNone: return "waiting for odometry";
    case TrackingStatus::kNotInitialized: return "not initialized";
    case TrackingStatus::kTracking: return "tracking";
    case TrackingStatus::kLost: return "LOST";
    case TrackingStatus::kRelocalized: return "relocalized";
  }
  return "?";
}

ViewerModel::ViewerModel(const ViewerModelOptions& options) : options_(options) {}

void ViewerModel::add_keyframe(const msg::Keyframe& message) {
  mirror_.add_keyframe(message);
  keyframe_of_frame_[message.frame_seq] = message.id;
  changed_ = true;
}

void ViewerModel::apply_keyframe_state(const msg::KeyframeState& message) {
  mirror_.apply_keyframe_state(message);
  changed_ = true;
}

void ViewerModel::apply_point_state(const msg::MapPointState& message) {
  mirror_.apply_point_state(message);
  if (message.merged_into != kNoId) merged_away_.insert(message.id);
  culled_points_.erase(message.id);
  changed_ = true;
}

void ViewerModel::point_disposed(PointId id) {
  // Samples of different topics arrive in any order: a point merged by a correction is not culled
  // even when its dispose comes before or after the correction.
  const MapPoint* point = mirror_.map().point(id);
  if (point != nullptr && merged_away_.count(id) == 0) culled_points_[id] = point->p_w;
  mirror_.point_disposed(id);
  changed_ = true;
}

void ViewerModel::apply_correction(const msg::LoopCorrection& message, Clock::time_point now) {
  for (const msg::PointMerge& merge : runtime::view(message.point_merges)) {
    loop_merged_points_.insert(merge.into_id);
    merged_away_.insert(merge.from_id);
    culled_points_.erase(merge.from_id);  // merged, not culled
  }
  ++loop_corrections_;
  loop_at_ = now;
  changed_ = true;
}

void ViewerModel::set_calibration(const msg::StereoCalibration& message) {
  rectifier_ = std::make_shared<const StereoRectifier>(messages::to_calibration(message));
  changed_ = true;
}

void ViewerModel::add_frame(const msg::StereoFrame& message) {
  FrameEntry entry;
  entry.seq = message.seq;
  entry.stamp_ns = message.stamp_ns;
  entry.raw_left = messages::to_grey_images(message).left.clone();  // the sample's buffer is reused
  if (last_seq_ && message.seq > *last_seq_ + 1) frames_.missed += message.seq - *last_seq_ - 1;
  if (!last_seq_ || message.seq > *last_seq_) last_seq_ = message.seq;
  ++frames_.received;
  frames_recent_.push_back(std::move(entry));
  while (frames_recent_.size() > kFrameRing) frames_recent_.pop_front();
  changed_ = true;
}

void ViewerModel::add_odometry(const msg::Odometry& message, Clock::time_point now) {
  OdometryEntry entry;
  switch (runtime::wire_value(message.state)) {  // any value may come (runtime/wire_enum.hpp)
    case heslam_msg_TRACKING_OK: entry.status = TrackingStatus::kTracking; break;
    case heslam_msg_TRACKING_INERTIAL_ONLY: entry.status = TrackingStatus::kTracking; break;  // the IMU's pose
    case heslam_msg_TRACKING_LOST: entry.status = TrackingStatus::kLost; break;
    default: entry.status = TrackingStatus::kNotInitialized; break;
  }
  if (entry.status == TrackingStatus::kTracking && was_lost_) relocalized_at_ = now, relocalized_ = true;
  if (entry.status != TrackingStatus::kNotInitialized) was_lost_ = entry.status == TrackingStatus::kLost;
  entry.stamp_ns = message.stamp_ns;
  entry.T_wc = messages::to_pose(message.T_wc);
  entry.reference = message.reference_keyframe_id;
  entry.T_ref_c = messages::to_pose(message.T_ref_c);
  entry.tracked_points = message.tracked_points;
  for (const msg::StageTime& stage : runtime::view(message.stage_times)) {
    if (std::string(stage.stage) == "total") entry.frame_time_ms = stage.ms;
  }
  if (!entry.T_wc.matrix().allFinite()) entry.status = TrackingStatus::kLost;  // never draw a NaN pose
  odometry_[message.seq] = entry;
  changed_ = true;
}

std::size_t ViewerModel::live_keyframes() const {
  return static_cast<std::size_t>(std::count_if(mirror_.map().keyframes.begin(), mirror_.map().keyframes.end(),
                                                [](const auto& entry) { return !entry.second.culled; }));
}

Pose3 ViewerModel::corrected_T_wc(const OdometryEntry& odometry) const {
  if (const Keyframe* reference = mirror_.map().keyframe(odometry.reference); reference != nullptr) {
    return reference->T_wc * odometry.T_ref_c;
  }
  return odometry.T_wc;
}

void ViewerModel::set_occupancy(OccupancyGrid grid, const Pose3& T_wg) {
  occupancy_ = std::make_shared<const OccupancyGrid>(std::move(grid));
  occupancy_T_wg_ = T_wg;
  changed_ = true;
}

Scene ViewerModel::scene(Clock::time_point now) {
  changed_ = false;
  Scene scene;
  scene.occupancy = occupancy_;
  scene.occupancy_T_wg = occupancy_T_wg_;
  const Map& map = mirror_.map();

  // Keyframes, the recent ones (newest ids: the frontend allocates them in creation order), graph.
  std::vector<KeyframeId> live;
  for (const auto& [id, keyframe] : map.keyframes) {
    if (keyframe.culled) continue;
    live.push_back(id);
    scene.keyframes_T_wc.push_back(keyframe.T_wc);
    for (const auto& [neighbour_id, weight] : keyframe.covisible) {
      const Keyframe* neighbour = map.keyframe(neighbour_id);
      if (neighbour_id > id && weight >= options_.covisibility_min_weight && neighbour != nullptr &&
          !neighbour->culled) {
        scene.covisibility.push_back({keyframe.T_wc.translation(), neighbour->T_wc.translation()});
      }
    }
    if (const Keyframe* parent = map.keyframe(keyframe.parent); parent != nullptr) {
      scene.spanning_tree.push_back({keyframe.T_wc.translation(), parent->T_wc.translation()});
    }
  }
  scene.map_keyframes = live.size();
  scene.map_version = map.version;
  const std::size_t recent_count = std::min(live.size(), static_cast<std::size_t>(options_.recent_keyframes));
  const std::set<KeyframeId> recent(live.end() - static_cast<std::ptrdiff_t>(recent_count), live.end());

  for (const auto& [id, point] : map.points) {
    PointCategory category = PointCategory::kMap;
    if (point.culled) {
      category = PointCategory::kCulled;
    } else if (loop_merged_points_.count(id) != 0) {
      category = PointCategory::kLoopMerged;
    } else if (recent.count(point.reference_kf) != 0) {
      category = PointCategory::kRecent;
    }
    if (category != PointCategory::kCulled) ++scene.map_points;
    scene.points.push_back({point.p_w, category});
  }
  for (const auto& [id, p_w] : culled_points_) scene.points.push_back({p_w, PointCategory::kCulled});

  if (mirror_.camera()) {
    scene.camera = *mirror_.camera();
  } else if (rectifier_) {
    scene.camera = rectifier_->camera();
  }

  // Trajectory and current camera.
  for (const auto& [seq, odometry] : odometry_) {
    if (!is_tracking(odometry.status)) continue;
    scene.trajectory_w.push_back(corrected_T_wc(odometry).translation());
    scene.trajectory_stamps_ns.push_back(odometry.stamp_ns);
  }
  const OdometryEntry* latest = odometry_.empty() ? nullptr : &odometry_.rbegin()->second;
  if (latest != nullptr && is_tracking(latest->status)) {
    scene.has_camera = true;
    scene.current_T_wc = corrected_T_wc(*latest);
  }

  // The frame: the newest one whose odometry is here (its features and status belong to it), else
  // the newest one.
  FrameEntry* frame = nullptr;
  for (auto it = frames_recent_.rbegin(); it != frames_recent_.rend() && frame == nullptr; ++it) {
    if (odometry_.count(it->seq) != 0) frame = &*it;
  }
  if (frame == nullptr && !frames_recent_.empty()) frame = &frames_recent_.back();
  if (frame != nullptr) {
    if (!frame->drawn) ++frames_.drawn;
    frame->drawn = true;
    scene.has_frame = true;
    scene.frame_seq = frame->seq;
    scene.frame_stamp_ns = frame->stamp_ns;
    scene.raw_left = frame->raw_left;  // shared, never written after add_frame
    scene.rectifier = rectifier_;
    if (auto odometry = odometry_.find(frame->seq); odometry != odometry_.end()) {
      scene.status = odometry->second.status;
      if (scene.status == TrackingStatus::kTracking && relocalized_ &&
          now - relocalized_at_ < options_.relocalized_shown) {
        scene.status = TrackingStatus::kRelocalized;
      }
      scene.frame_time_ms = odometry->second.frame_time_ms;
      scene.tracked_points = odometry->second.tracked_points;
      add_map_features(scene, *frame);
      if (!scene.frame_is_keyframe && is_tracking(odometry->second.status))
        add_projected_points(scene, odometry->second);
    }
  }
  scene.loop_corrections = loop_corrections_;
  scene.loop_flash = loop_corrections_ > 0 && now - loop_at_ < options_.loop_flash;
  return scene;
}

void ViewerModel::add_map_features(Scene& scene, const FrameEntry& frame) const {
  auto it = keyframe_of_frame_.find(frame.seq);
  if (it == keyframe_of_frame_.end()) return;
  const Keyframe* keyframe = mirror_.map().keyframe(it->second);
  if (keyframe == nullptr) return;
  scene.frame_is_keyframe = true;
  const StereoFeatures& features = keyframe->features;
  for (std::size_t i = 0; i < features.size(); ++i) {
    const bool matched = i < keyframe->point_ids.size() && keyframe->point_ids[i] != kNoId;
    if (!matched && !features.has_stereo(i)) continue;
    scene.features.push_back({cv::Point2f(features.keypoints[i].u_px, features.keypoints[i].v_px),
                              matched ? SceneFeature::Kind::kMapMatch : SceneFeature::Kind::kStereoOnly});
  }
}

void ViewerModel::add_projected_points(Scene& scene, const OdometryEntry& odometry) const {
  const Map& map = mirror_.map();
  const Keyframe* reference = map.keyframe(odometry.reference);
  if (reference == nullptr || !(scene.camera.fx_px > 0.0)) return;
  std::vector<const Keyframe*> local{reference};
  for (const auto& [id, weight] : reference->covisible) {
    if (local.size() > kProjectedNeighbours) break;
    if (const Keyframe* neighbour = map.keyframe(id); neighbour != nullptr) local.push_back(neighbour);
  }
  std::set<PointId> seen;
  const Pose3 T_cw = corrected_T_wc(odometry).inverse();
  for (const Keyframe* keyframe : local) {
    for (const PointId id : keyframe->point_ids) {
      if (id == kNoId || !seen.insert(id).second) continue;
      const MapPoint* point = map.point(id);
      if (point == nullptr || point->culled) continue;
      const Eigen::Vector3d p_c = T_cw * point->p_w;
      if (p_c.z() <= 0.0) continue;
      const Eigen::Vector2d uv = scene.camera.project(p_c);
      if (!scene.camera.in_image(uv.x(), uv.y())) continue;
      scene.features.push_back({cv::Point2f(static_cast<float>(uv.x()), static_cast<float>(uv.y())),
                                SceneFeature::Kind::kProjectedMapPoint});
    }
  }
}

}  // namespace heslam::viewer
