// heslam-frontend: the stereo tracking process. A thin DDS adapter over FrameProcessor (rectify ->
// HE -> ORB -> stereo -> Tracker): takes the calibration and stereo frames, publishes odometry per
// frame, immutable keyframes, FrameDone acknowledgements (lockstep) and its status; mirrors the local
// mapper's keyframe / point state into the tracker's map when a mapper runs.
#pragma once

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/core/mapping/map_file.hpp"
#include "components/frontend/batched_mirror.hpp"
#include "components/frontend/frame_processor.hpp"
#include "components/frontend/frontend_options.hpp"
#include "components/frontend/inertial_frontend.hpp"
#include "components/frontend/odometry_journal.hpp"
#include "components/messages/imu_input.hpp"
#include "components/messages/odometry.hpp"
#include "runtime/checked_reader.hpp"
#include "runtime/component.hpp"
#include "runtime/role_binding.hpp"

namespace heslam::frontend {

// A saved map (--session, --localize) of another camera than the run's calibration: ends the process.
class SavedMapCameraMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Frontend : public runtime::Component {
 public:
  explicit Frontend(const runtime::CommonArgs& args);

 private:
  void configure(const runtime::Config& config) override;
  void run() override;
  bool accepts_positional_args() const override { return true; }  // --mapper-map-file FILE

  // With a journal: resume after the frames a previous process of this run finished, and publish
  // their odometry again (a recorder that was down meanwhile gets it from our history).
  void resume_from_journal();
  // The mapper's map file, if this run's mapper wrote it (FILE.run): a restarted frontend resumes
  // in it whether or not the mapper is running right now.
  bool mapper_map_file_of_this_run() const;
  // One warning when the settings file's Camera.fx / Camera.bf are not the data's calibration.
  void warn_if_settings_disagree(const PinholeStereo& camera);
  void take_calibration();
  // At the end of the run: frames still queued (real time, the replay ended while we were busy)
  // are not tracked but counted as missed, so every published frame is processed or missed.
  void count_frames_left();
  void take_frames();
  // Real time, behind the camera: skips the frame just taken when it is stale and a newer one waits
  // (realtime.shed_frames_after_ms), counted as shed. True when skipped.
  bool shed_stale_frame();
  // After missed or shed frames: the tracker starts from the last motion scaled to the gap.
  void predict_over_gap(std::uint64_t seq);
  // published_ns: the frame's write time by its publisher (0: unknown), for the latency stage.
  void process_frame(const msg::StereoFrame& frame, std::int64_t published_ns);
  // One line with the samples refused from other participants (invalid, second writers), if any.
  void log_rejections();
  // Applies whatever map state the mapper published so far.
  void mirror_map_state();
  // The tracker's last frame follows its reference keyframe after a loop correction (ORB-SLAM2's
  // UpdateLastFrame); the jump is kept in T_wo_.
  void follow_loop_correction();
  // The atlas (docs/frontend.md, Atlas): counts and logs a new map, and when the tracked map changed
  // (a new map, or relocalized in another one) moves T_wo_ so that Odometry.T_oc does not jump.
  void follow_map_change(const TrackResult& result, std::uint64_t seq);
  // With a mapper: mirror its stored map into a new processor's tracker and, when it holds
  // keyframes (this frontend was restarted), relocalize in it instead of starting a new map.
  void resume_in_mapper_map();
  // --session / --localize: a saved map of another camera than the calibration's ends the process
  // (SavedMapCameraMismatch, one line); a map without a camera (format < 4) is not checked.
  void check_saved_map_camera(const MapSnapshot& snapshot) const;
  // --session: a restarted frontend continues its session (the atlas's rule at once).
  void configure_session();
  // --session: at the first frame with a pose, the atlas's own rule from then on; one line saying
  // whether the session was relocalized in the saved map or started a map of its own.
  void follow_session_start(const TrackResult& result, std::uint64_t seq);
  // The mapper's keyframes with their features from DDS (topics().mapper_keyframes()): for a
  // restarted frontend without a readable map file of the run. Empty when no mapper publishes them
  // within kMapHistoryWait.
  Map mapper_keyframes_from_dds();
  // Lockstep with a mapper (and a loop closer): waits for the KeyframeDone(id) of each, mirroring
  // state meanwhile, until the mirror holds the map version they acknowledged. False on timeout or
  // shutdown.
  bool wait_for_keyframe_done(KeyframeId id);
  // The same, timed: the `keyframe_wait` stage.
  bool timed_wait_for_keyframe_done(KeyframeId id);
  bool keyframe_acknowledged(KeyframeId id) const;
  // One KeyframeDone as taken: who wrote it, the role it claims (runtime/role_binding.hpp), its fields.
  struct HeldKeyframeDone {
    dds_instance_handle_t writer;
    std::string role;
    std::string component;
    std::uint64_t keyframe_id;
    std::uint64_t map_version;
    std::uint64_t correction_id;
    // What the role binding remembers it acknowledged: the correction for a correction's acknowledgement (its
    // keyframe_id is the loop's keyframe, which has an acknowledgement of its own), else the keyframe.
    std::uint64_t subject() const { return correction_id != 0 ? correction_id : keyframe_id; }
  };
  // An acknowledgement of a writer that holds its role: what it says is acted upon.
  void use_keyframe_done(const HeldKeyframeDone& done);
  void acknowledge(const msg::StereoFrame& frame, const FrameOutput* output);

  // Inertial tracking (options_.inertial.enabled; docs/frontend.md, Inertial tracking).
  void configure_inertial();
  // Takes the IMU calibration and readings that arrived into inertial_ (never waits).
  void take_imu();
  // Lockstep: waits until the IMU covers the frame's stamp, its stream ended, or imu.wait_s passed
  // (then the IMU is off: one warning, stereo-only).
  void wait_for_imu(const msg::StereoFrame& frame);
  // Before tracking the frame: the IMU's prediction into the tracker; a dead IMU turns it off.
  void predict_inertial(const msg::StereoFrame& frame);
  // After tracking it: the inertial state follows; the odometry gets the velocity when inertial.
  void update_inertial(const msg::StereoFrame& frame, const TrackResult& result, messages::OdometryMessage& odometry);
  void turn_inertial_off(const std::string& reason);
  // The IMU's counters on the status topic, and its state as the status message (the run's last line).
  void report_inertial();
  std::string inertial_summary();

  FrontendOptions options_;
  // Checked, one writer each (runtime/checked_reader.hpp): a second replay or a stray participant on
  // the domain is ignored instead of mixed into the run.
  std::optional<runtime::CheckedReader<msg::StereoCalibration>> calibration_reader_;
  std::optional<runtime::CheckedReader<msg::StereoFrame>> frame_reader_;
  std::optional<runtime::CheckedReader<msg::KeyframeState>> keyframe_state_reader_;
  std::optional<runtime::CheckedReader<msg::MapPointState>> point_state_reader_;
  std::optional<runtime::Reader<msg::KeyframeDone>> keyframe_done_reader_;
  // Who may acknowledge keyframes: the first writer of each component name's KeyframeDone (the
  // mapper's, each loop closer's); a second live one is a conflict (runtime/role_binding.hpp).
  std::optional<runtime::RoleBinding> keyframe_done_roles_;
  // KeyframeDone of a writer that claimed a role while its first writer was still matched (a
  // restarted mapper within the killed one's lease): used once it takes the role over.
  std::vector<HeldKeyframeDone> held_keyframe_done_;
  std::optional<runtime::Writer<msg::Odometry>> odometry_writer_;
  std::optional<runtime::Writer<msg::Keyframe>> keyframe_writer_;
  std::optional<runtime::Writer<msg::FrameDone>> frame_done_writer_;
  std::optional<OdometryJournal> journal_;
  // The last journaled frame of a previous process of this run, when it was tracked: the restarted
  // tracker continues from it instead of relocalizing.
  std::optional<LastFramePose> journal_last_pose_;
  std::unique_ptr<runtime::WaitSet> waitset_;
  std::unique_ptr<FrameProcessor> processor_;  // from the first calibration
  std::optional<PinholeStereo> calibration_camera_;
  // The writer of the calibration in use: only it may change the calibration (a different one from
  // any other writer, even one that took over the topic, is refused).
  dds_instance_handle_t calibration_writer_ = 0;
  std::deque<runtime::Received<msg::StereoFrame>> pending_;  // frames before the calibration
  runtime::Received<msg::StereoFrame> frame_;                // taken into, buffers reused frame to frame
  // Seq of the last frame processed: a jump counts the frames in between as missed (a real-time
  // publisher outran us and the image reader kept only the newest), so a drop is never silent.
  std::optional<std::uint64_t> last_seq_;
  // Frames of the journal published but not finished (a keyframe's frame, killed while waiting for
  // the mapper): tracked again after the restart, they count once in odometry_frames.
  std::set<std::uint64_t> resumed_unfinished_seqs_;
  // KeyframeDone seen, not yet waited for: keyframe -> components that acknowledged it.
  std::map<KeyframeId, std::set<std::string>> keyframes_done_;
  std::uint64_t acknowledged_map_version_ = 0;  // the largest map version an awaited ack reported
  // The mapper's states, applied one complete map version at a time; its version() is the mapper's
  // map version this mirror holds (the tracker's own map.version also counts the keyframes it
  // inserted, so it cannot say that).
  BatchedMirror mirror_;
  GapPrediction gap_prediction_;  // the last motion, for a frame after a gap (realtime.predict_over_gaps)
  // odom -> world (REP 105 map -> odom): the loop corrections followed so far, left out of Odometry.T_oc.
  Pose3 T_wo_ = Pose3::Identity();
  std::optional<MapId> odometry_map_;    // the map of the last frame published with a pose
  Pose3 last_T_oc_ = Pose3::Identity();  // ... and its odometry pose
  // Inertial tracking: the readers, the stream's continuity, the state (null when off by option).
  std::optional<messages::ImuInput> imu_input_;
  std::unique_ptr<runtime::WaitSet> imu_waitset_;  // the IMU readers only: the lockstep wait
  std::unique_ptr<InertialFrontend> inertial_;
  std::map<std::string, std::uint64_t> imu_counters_reported_;
  std::optional<std::uint64_t> inertial_initialized_at_seq_;
  // --localize: the seq of the first frame tracked in the saved map, unset until then.
  std::optional<std::uint64_t> relocalized_at_seq_;
  // --session (multi-session mapping): the first frame with a pose, relocalized in the saved map or the
  // first of a new map; until then the session's new-map rule (session.new_map_after_s) holds.
  bool session_started_ = false;
};

}  // namespace heslam::frontend
