// heslam-occupancy's component: a reader of the map like the loop closer, it never writes map state.
//
// DDS thread: raw frames (camera/stereo) go into a ring by stamp; a keyframe (map/keyframes) takes
// the frame whose stamp equals its own and queues it for the worker; keyframe states
// (map/keyframe_states: refined poses, loop corrections as the mapper applied them, culling) update
// the poses. Worker thread: rectify, equalize as the frontend does, dense disparity, the keyframe's
// cloud (its camera frame), fusion; a map made stale by moved keyframes is fused again at most every
// rebuild_period_s. The frontend never waits for this process: frames are read from the replay's
// topic, which the frontend reads too.
//
// At the end: every cloud fused again at the final poses in keyframe id order, STEM.pgm + STEM.yaml
// (map_server) and STEM.ply written. Restarted, it loads the clouds of its state folder and takes
// the keyframes and states again from DDS (transient-local), so its map is the one it had.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/image/histogram_equalizer.hpp"
#include "components/core/occupancy/dense_stereo.hpp"
#include "components/core/occupancy/multiview_depth.hpp"
#include "components/core/occupancy/occupancy_map.hpp"
#include "components/occupancy/occupancy_options.hpp"
#include "runtime/component.hpp"
#include "runtime/writer.hpp"

namespace heslam::occupancy {

class OccupancyNode final : public runtime::Component {
 public:
  explicit OccupancyNode(const runtime::CommonArgs& args);
  ~OccupancyNode() override;

 private:
  struct Frame {
    std::int64_t stamp_ns = 0;
    cv::Mat left;  // raw 8-bit grey, owned
    cv::Mat right;
  };
  // Work for the worker, in arrival order: a keyframe's frame to turn into a cloud, or a pose update.
  struct Job {
    enum class Kind { kCloud, kPose, kCull, kSave, kUp } kind = Kind::kCloud;
    std::uint64_t keyframe_id = 0;
    Frame frame;                                     // kCloud
    Pose3 T_wc = Pose3::Identity();                  // kPose; kCloud: the keyframe sample's (multi-view refinement)
    std::uint64_t request_id = 0;                    // kSave: the map as it is now, to ...
    std::filesystem::path stem;                      // ... STEM.pgm + STEM.yaml + STEM.ply
    Eigen::Vector3d up_w = Eigen::Vector3d::Zero();  // kUp: against the odometry's gravity, world frame
  };
  struct PendingKeyframe {
    std::uint64_t id = 0;
    std::int64_t stamp_ns = 0;
    // The frontend's pose in the keyframe sample: the multi-view refinement uses it (not the mapper's
    // later one), so its result does not depend on when the mapper's state arrives.
    Pose3 T_wc = Pose3::Identity();
  };

  void configure(const runtime::Config& config) override;
  void run() override;
  bool accepts_positional_args() const override { return true; }  // its own flags (OccupancyProcessOptions)

  void take_all();
  void on_frame(const msg::StereoFrame& message);
  void on_keyframe(const msg::Keyframe& message);
  // grid.up_from_gravity: a valid gravity on the odometry becomes the grid's up (kUp job) when it moved.
  void on_odometry(const msg::Odometry& message);
  // A kUp job for the worker: the grid's up becomes up_w (remembered as the one last sent).
  void send_up(const Eigen::Vector3d& up_w);
  // Worker thread: the views of the state folder into a new multiview_; a kept view into the state folder.
  void restore_views();
  void keep_view(std::uint64_t keyframe_id, const cv::Mat& left, const Pose3& T_wc);
  // The angle between a world direction and grid.up's axis, degrees.
  double up_tilt_deg(const Eigen::Vector3d& up_w) const;
  void on_keyframe_state(const msg::KeyframeState& message);
  // Pending keyframes whose frame is in the ring go to the worker; those older than the newest frame
  // without theirs are skipped (counted).
  void match_pending();
  void worker_loop();
  void make_cloud(const Job& job);
  void push(Job job);
  void load_state();
  void write_outputs();
  void log_stages();
  // STEM.first_poses.pgm + .yaml: the clouds of the final map fused at their keyframes' first poses.
  void write_first_poses_grid();
  // Worker thread (the DDS thread at the end): the grid when it changed and its period passed, the
  // cloud when its period passed; final: both, whatever the periods.
  void publish_live(bool final);
  // Worker thread: a save request (map/occupancy_save_request) answered on map/occupancy_save_reply.
  void save_on_request(const Job& job);

  OccupancyProcessOptions options_;
  std::optional<runtime::Reader<msg::StereoCalibration>> calibration_reader_;
  std::optional<runtime::Reader<msg::StereoFrame>> frame_reader_;
  std::optional<runtime::Reader<msg::Keyframe>> keyframe_reader_;
  std::optional<runtime::Reader<msg::KeyframeState>> keyframe_state_reader_;
  std::optional<runtime::Reader<msg::Odometry>> odometry_reader_;  // grid.up_from_gravity: the IMU's gravity
  std::unique_ptr<runtime::WaitSet> waitset_;
  std::optional<runtime::Writer<msg::OccupancyGrid2D>> grid_writer_;
  std::optional<runtime::Writer<msg::DenseCloud>> cloud_writer_;
  std::optional<runtime::Reader<msg::OccupancySaveRequest>> save_reader_;
  std::optional<runtime::Writer<msg::OccupancySaveReply>> save_writer_;

  // DDS thread only.
  std::deque<Frame> ring_;
  std::deque<PendingKeyframe> pending_;
  std::map<std::uint64_t, bool> seen_keyframes_;  // ids whose cloud is queued, loaded or skipped
  std::map<std::uint64_t, bool> has_state_;       // ids with a mapper state (their pose is the mapper's)
  std::set<std::uint64_t> culled_ids_;            // ids the mapper culled
  std::map<std::uint64_t, Pose3> first_poses_;    // each keyframe's pose in its keyframe sample
  // Against the newest gravity on the odometry, and the one last sent to the worker (kUp).
  std::optional<Eigen::Vector3d> latest_up_w_;
  std::optional<Eigen::Vector3d> sent_up_w_;

  // Shared with the worker (mutex_).
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Job> jobs_;
  std::shared_ptr<const StereoRectifier> rectifier_;

  // Worker thread only (and the DDS thread before the worker starts and after it stopped).
  std::unique_ptr<OccupancyMap> map_;
  std::optional<HistogramEqualizer> equalizer_;
  std::optional<DenseStereo> stereo_;
  std::optional<MultiViewDepth> multiview_;  // options_.multiview enabled: the last keyframes' left images
  // Its kept views on disk (STATE/ID.view): loaded at start, given to multiview_ once it exists; the
  // files of the views it keeps, oldest first; the next view's sequence number.
  struct KeptViewFile {
    std::uint64_t sequence = 0;
    std::uint64_t keyframe_id = 0;
  };
  std::vector<KeptView> loaded_views_;
  std::deque<KeptViewFile> kept_views_;
  std::uint64_t next_view_sequence_ = 0;
  std::optional<Eigen::Vector3d> up_w_;  // the grid's up from gravity, once the odometry gave one
  std::size_t up_changes_ = 0;
  // Keyframes refined against at least one neighbour, and their pixels (with a disparity / refined).
  std::size_t multiview_keyframes_ = 0;
  std::size_t multiview_pixels_ = 0;
  std::size_t multiview_refined_ = 0;
  bool stop_ = false;
  // Live outputs (worker thread): whether the map changed since the last grid / cloud, when they went.
  bool grid_dirty_ = false;
  bool cloud_dirty_ = false;
  std::optional<OccupancyGrid> published_grid_;
  std::chrono::steady_clock::time_point grid_sent_{};
  std::chrono::steady_clock::time_point cloud_sent_{};
  std::uint64_t grid_revision_ = 0;
  std::uint64_t cloud_revision_ = 0;
  bool busy_ = false;
  std::thread worker_;
  std::exception_ptr worker_error_;
};

}  // namespace heslam::occupancy
