// The viewer's state, fed by the DDS thread: the map mirrored from the transient-local topics
// (loop_closer::MapMirror), what the mirror forgets but the viewer shows (culled points, points merged
// by a loop closure), the latest frames and odometry, and the counts. scene() copies out what one
// drawing needs. Not thread-safe: the node guards it with one mutex.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/loop_closer/map_mirror.hpp"
#include "runtime/messages.hpp"
#include "tools/viewer/scene.hpp"

namespace heslam::viewer {

struct ViewerModelOptions {
  int recent_keyframes = 5;  // see ViewerOptions
  int covisibility_min_weight = 100;
  // How long the 2D view flashes after a loop correction arrives.
  std::chrono::milliseconds loop_flash{1500};
  // How long "relocalized" is shown after tracking came back from lost.
  std::chrono::milliseconds relocalized_shown{2000};
};

// Frame counts: received = drawn + not_drawn (replaced by a newer frame before the drawing thread
// got to it); missed = seq gaps (never delivered: the best-effort keep-last reader dropped them).
struct FrameCounts {
  std::uint64_t received = 0;
  std::uint64_t drawn = 0;
  std::uint64_t missed = 0;
  std::uint64_t not_drawn() const { return received - drawn; }
};

class ViewerModel {
 public:
  using Clock = std::chrono::steady_clock;
  explicit ViewerModel(const ViewerModelOptions& options);

  // Map topics. Throw std::runtime_error naming the sample when it is malformed (model unchanged).
  void add_keyframe(const msg::Keyframe& message);
  void apply_keyframe_state(const msg::KeyframeState& message);
  void apply_point_state(const msg::MapPointState& message);
  void point_disposed(PointId id);
  void apply_correction(const msg::LoopCorrection& message, Clock::time_point now);

  // Throws std::runtime_error naming the calibration source when it is unusable.
  void set_calibration(const msg::StereoCalibration& message);
  // Throws std::runtime_error naming the frame when the image bytes do not match its size.
  void add_frame(const msg::StereoFrame& message);
  void add_odometry(const msg::Odometry& message, Clock::time_point now);
  // heslam-occupancy's newest 2D grid (replaces the previous one); T_wg: grid frame -> world.
  void set_occupancy(OccupancyGrid grid, const Pose3& T_wg);

  // Everything one drawing shows; marks the chosen frame drawn.
  Scene scene(Clock::time_point now);
  // True when anything changed since the last scene().
  bool changed() const { return changed_; }

  const FrameCounts& frame_counts() const { return frames_; }
  const Map& map() const { return mirror_.map(); }
  std::uint64_t loop_corrections() const { return loop_corrections_; }
  std::size_t live_keyframes() const;
  // Any frame, odometry or map sample arrived.
  bool received_anything() const {
    return frames_.received > 0 || !odometry_.empty() || !mirror_.map().keyframes.empty() ||
           !mirror_.map().points.empty();
  }

 private:
  struct FrameEntry {
    std::uint64_t seq = 0;
    std::int64_t stamp_ns = 0;
    cv::Mat raw_left;
    bool drawn = false;
  };
  struct OdometryEntry {
    TrackingStatus status = TrackingStatus::kNone;
    std::int64_t stamp_ns = 0;
    Pose3 T_wc = Pose3::Identity();
    KeyframeId reference = kNoId;
    Pose3 T_ref_c = Pose3::Identity();
    double frame_time_ms = 0.0;
    std::uint32_t tracked_points = 0;
  };

  // The pose with the reference keyframe's current (refined, loop-corrected) pose when known.
  Pose3 corrected_T_wc(const OdometryEntry& odometry) const;
  void add_map_features(Scene& scene, const FrameEntry& frame) const;
  void add_projected_points(Scene& scene, const OdometryEntry& odometry) const;

  ViewerModelOptions options_;
  loop_closer::MapMirror mirror_;
  std::map<PointId, Eigen::Vector3d> culled_points_;       // last known position of disposed points
  std::set<PointId> loop_merged_points_;                   // targets of a loop correction's merges
  std::set<PointId> merged_away_;                          // merged into another point: gone, not culled
  std::map<std::uint64_t, KeyframeId> keyframe_of_frame_;  // frame seq -> keyframe made from it
  std::shared_ptr<const StereoRectifier> rectifier_;       // immutable once made: shared with drawings
  std::deque<FrameEntry> frames_recent_;                   // newest last
  std::map<std::uint64_t, OdometryEntry> odometry_;        // by frame seq, every frame seen (trajectory)
  std::optional<std::uint64_t> last_seq_;
  bool was_lost_ = false;
  Clock::time_point relocalized_at_{};
  bool relocalized_ = false;
  Clock::time_point loop_at_{};
  std::uint64_t loop_corrections_ = 0;
  FrameCounts frames_;
  std::shared_ptr<const OccupancyGrid> occupancy_;  // immutable once made: shared with drawings
  Pose3 occupancy_T_wg_ = Pose3::Identity();
  bool changed_ = false;
};

}  // namespace heslam::viewer
