// A loop closer process's DDS side, shared by every implementation (heslam-loop-closer with bag of
// words, heslam-loop-closer-proximity): mirrors the map from the transient-local map topics, runs the
// core LoopClosing on each keyframe once the local mapper acknowledged it, publishes LoopCorrections,
// waits for the mapper to apply them and acknowledges the keyframe (lockstep). Implementations only
// say how loop candidates are found (make_detector).
//
// Restart: with a state file this run wrote, keyframes already processed are skipped (the last one is
// acknowledged again, a lockstep frontend may wait for it) and the loops closed are restored.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "components/core/imu/imu_buffer.hpp"
#include "components/core/loop/global_inertial_chain.hpp"
#include "components/core/loop/loop_closing.hpp"
#include "components/core/map/agent_guard.hpp"
#include "components/loop_closer/background_global_ba.hpp"
#include "components/loop_closer/loop_closer_options.hpp"
#include "components/loop_closer/map_mirror.hpp"
#include "components/messages/imu_input.hpp"
#include "runtime/checked_reader.hpp"
#include "runtime/component.hpp"
#include "runtime/role_binding.hpp"
#include "runtime/run_end_watch.hpp"
#include "runtime/run_journal.hpp"

namespace heslam::loop_closer {

class LoopCloserNode : public runtime::Component {
 public:
  LoopCloserNode(std::string default_name, const runtime::CommonArgs& args);

 protected:
  // The implementation's loop candidate detector, built once the options are read (configure()).
  virtual std::unique_ptr<LoopDetector> make_detector(const runtime::Config& config,
                                                      const LoopCloserProcessOptions& options) = 0;

 private:
  void configure(const runtime::Config& config) override;
  void run() override;
  bool accepts_positional_args() const override { return true; }  // --state-file, --vocabulary

  // Takes every sample waiting in the readers into the mirror and the acknowledgement tables;
  // returns how many it took. The mirror's map version then is the mapper's version it holds
  // completely (version markers), so a keyframe acknowledged at version v is processed only on it.
  std::size_t take_all();
  // A keyframe sample taken, and when (held while the mapper's state of its map is on its way).
  struct KeyframeAwaitingMap {
    runtime::Received<msg::Keyframe> received;
    std::chrono::steady_clock::time_point since;
  };
  enum class Admission { kAdmitted, kWait, kRefused };
  // --agents N > 1: whether a keyframe of this run's frontends passes the AgentKeyframeGuard; a refused
  // one is counted (refused_agent_keyframes), named in one line and acknowledged. One refused only
  // because its map is unknown waits up to kAwaitMapState for the mapper's states of that map.
  Admission admit_agent_keyframe(const KeyframeAwaitingMap& candidate, std::chrono::steady_clock::time_point now);
  void process_ready_keyframes();
  // The atlas: a place of another map recognised from keyframe `id` (no loop was closed there).
  LoopClosingResult process_merge(KeyframeId id);
  void process_keyframe(KeyframeId id);
  // Waits for the global BA started last and publishes its correction (if it was not aborted).
  void finish_global_ba();
  // Returns the free heap to the system after a burst (the global BA thread's arena, a correction's
  // solver); counted as heap_released_kib, timed as stage heap_release (runtime/heap.hpp).
  void release_heap(const char* after);
  // Publishes the correction and waits until the mapper applied it and the mirror holds the result.
  bool publish_and_wait(LoopCorrection correction);
  void acknowledge(KeyframeId id);
  // Inertial runs (options_.gravity_from_odometry): the odometry's gravity by frame stamp.
  void take_odometry();
  // False while the keyframe should wait for the odometry of its frame (an inertial run, bounded).
  bool odometry_covers(const Keyframe& keyframe);
  // Before processing keyframe `id`: the 4-DoF pose graph about the gravity of its frame, if there is one.
  void choose_pose_graph(KeyframeId id);
  // --mapper-map-file: the map the local mapper loaded (a session on a saved map) into the mirror.
  void load_mapper_map();
  // Global BA with IMU factors (options_.global_ba_imu): takes the IMU readings and the IMU's and the
  // camera's calibrations into imu_buffer_ (bounded by options_.imu_buffer_s).
  void take_imu();
  // The IMU chain for a global BA on the mirror's map, or nullopt (not an inertial run, no calibration,
  // no readings). Lockstep: waits (at most options_.imu_wait_s) for the IMU to cover the newest keyframe.
  std::optional<GlobalInertialInput> inertial_input();
  void load_state();
  void save_state();
  void log_summary();

  LoopCloserProcessOptions options_;
  std::unique_ptr<runtime::WaitSet> waitset_;
  // Started by hand into a run (HESLAM_RUN_ID): ends when the run's supervisor ends it.
  std::optional<runtime::RunEndWatch> run_end_;
  bool run_supervisor_seen_ = false;  // said once: from then on the run's end ends this process
  // One writer each (runtime/checked_reader.hpp); the mirror checks the samples (messages::check).
  std::optional<runtime::CheckedReader<msg::Keyframe>> keyframe_reader_;
  std::optional<runtime::CheckedReader<msg::KeyframeState>> keyframe_state_reader_;
  std::optional<runtime::CheckedReader<msg::MapPointState>> point_state_reader_;
  std::optional<runtime::Reader<msg::KeyframeDone>> keyframe_done_reader_;
  // Who may acknowledge as each component (the first writer of its name); a second live one is a
  // conflict the run fails on (runtime/role_binding.hpp). Acknowledgements of a
  // second writer wait here until its predecessor is gone (a restarted mapper).
  std::optional<runtime::RoleBinding> keyframe_done_roles_;
  struct HeldKeyframeDone {
    dds_instance_handle_t writer;
    std::string component;
    std::uint64_t keyframe_id;
    std::uint64_t map_version;
    std::uint64_t correction_id;
    bool held = false;  // asked about before (runtime::RoleBinding::claim's `again`)
    // What the role binding remembers it acknowledged: the correction, or the keyframe (as the frontend's).
    std::uint64_t subject() const { return correction_id != 0 ? correction_id : keyframe_id; }
  };
  std::vector<HeldKeyframeDone> held_keyframe_done_;
  // The frontend's odometry, for its gravity (inertial runs): gravity_valid samples by stamp, the newest
  // stamp taken, and since when (steady clock) the next keyframe has been waiting for its frame's sample.
  std::optional<runtime::CheckedReader<msg::Odometry>> odometry_reader_;
  std::map<std::int64_t, Eigen::Vector3d> gravity_by_stamp_;
  std::int64_t newest_odometry_stamp_ = 0;
  std::optional<std::chrono::steady_clock::time_point> odometry_wait_since_;
  bool four_dof_announced_ = false;
  // The IMU for the global BA (options_.global_ba_imu; docs/loop_closer.md, Global BA with IMU factors).
  std::optional<messages::ImuInput> imu_input_;
  std::unique_ptr<ImuBuffer> imu_buffer_;
  std::set<std::string> imu_warned_;  // one warning per kind, then counted only
  std::optional<runtime::Writer<msg::LoopCorrection>> correction_writer_;
  std::optional<runtime::Writer<msg::KeyframeDone>> keyframe_done_writer_;

  std::unique_ptr<LoopDetector> detector_;  // moved into closing_ once the camera is known
  std::unique_ptr<LoopClosing> closing_;
  BackgroundGlobalBa global_ba_;                           // after closing_: stopped before closing_ goes
  MapMirror mirror_{KeyframeAdmission::kWithMapperState};  // loop closing on mapped keyframes only
  std::optional<AgentKeyframeGuard> agent_guard_;          // --agents N > 1: several frontends (docs/agents.md)
  std::vector<KeyframeAwaitingMap> awaiting_map_;          // keyframes whose map no state has named yet
  std::set<KeyframeId> refused_;                           // keyframes the agent guard refused (acknowledged already)
  std::map<KeyframeId, std::uint64_t> mapped_;             // mapper acknowledged: keyframe -> map version
  std::map<std::uint64_t, std::uint64_t> corrections_applied_;  // correction id -> map version after it
  std::optional<runtime::RunJournal> state_file_;               // with options_.state_file
  std::map<std::uint8_t, KeyframeId> last_processed_;           // by creator tag (each agent's ids grow on their own)
  std::uint64_t correction_counter_ = 0;
  std::vector<std::pair<KeyframeId, KeyframeId>> restored_loops_;
  bool reader_wait_done_ = false;
};

}  // namespace heslam::loop_closer
