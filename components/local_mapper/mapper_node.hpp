// heslam-local-mapper's DDS side: takes Keyframe samples (transient-local, keyed) and LoopCorrection
// samples, runs the core LocalMapper on them in keyframe-id order, persists the map, publishes
// KeyframeState / MapPointState for exactly what changed (removed points disposed) and a KeyframeDone
// per keyframe and per applied correction (lockstep: a loop closer waits for the latter).
//
// Restart: with a map_file that this run (same heslam-supervisor) wrote, the mapper resumes from it;
// a file of an earlier run is replaced. The Keyframe samples DDS still
// holds arrive again; those the file has are skipped (the last one is acknowledged again, a waiting
// frontend may need it), the others are processed, so a kill -9 loses no keyframe. A file from a
// different run (same keyframe id, different stamp) is discarded with a warning.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/agent_guard.hpp"
#include "components/core/mapping/inertial_mapping.hpp"
#include "components/core/mapping/local_mapper.hpp"
#include "components/core/mapping/map_journal.hpp"
#include "components/local_mapper/mapper_process_options.hpp"
#include "components/messages/imu_input.hpp"
#include "components/messages/keyframe.hpp"
#include "runtime/checked_reader.hpp"
#include "runtime/component.hpp"
#include "runtime/run_journal.hpp"

namespace heslam::local_mapper {

class MapperNode : public runtime::Component {
 public:
  explicit MapperNode(const runtime::CommonArgs& args);

 private:
  struct PendingKeyframe {
    messages::DecodedKeyframe decoded;
    PinholeStereo camera;
  };

  void configure(const runtime::Config& config) override;
  void run() override;
  bool accepts_positional_args() const override { return true; }

  void load_initial_map();
  // --save-map: the final map into `path`. Throws (the process then exits 1) when there is none.
  void save_map_to(const std::filesystem::path& path);
  // After save_map_to with a loaded map (a session): one line, the loaded and the new keyframes.
  void log_session_map(const std::filesystem::path& path);
  // --agents N > 1: whether a keyframe of this run's frontends passes the AgentKeyframeGuard; a refused
  // one is counted (refused_agent_keyframes), named in one line and acknowledged.
  bool admit_agent_keyframe(const msg::Keyframe& message, dds_instance_handle_t writer);
  void take_keyframes();
  void take_corrections();
  void process_pending();
  void map_keyframes_left_at_stop();  // after SIGTERM: the frontend's last keyframes, bounded
  void process_keyframe(PendingKeyframe keyframe);
  void start_mapper(const PendingKeyframe& first);
  void apply_corrections();

  void record(const MapChanges& changes);
  void report_size(const std::string& name, std::uint64_t now, std::uint64_t& reported);
  // Persists what changed since the last save (unsaved_changes_): a journal record, or a snapshot.
  void save();
  // map_journal.verify: the file loaded back must be the map in memory (throws otherwise).
  void verify_map_file();
  // `correction_id`: the changes are that loop correction's (marked on the version marker).
  void publish(const MapChanges& changes, std::uint64_t correction_id = 0);
  // Every keyframe and point state of `map`; then, for a resumed map, the points `removed` (id ->
  // merged_into) that the map no longer holds are disposed again (their merge sample first).
  void publish_all(const Map& map, const std::map<PointId, PointId>& removed = {});
  // Before a save: the points the step being saved removes, to FILE.removed (map_removed_path), so a
  // mapper killed after the save and before the publication's end disposes them again when it resumes.
  void write_removed_points(const std::map<PointId, PointId>& removed);
  // What FILE.removed holds (empty when none or unreadable: one warning).
  std::map<PointId, PointId> read_removed_points();
  // test.kill_after_saved_keyframes: SIGKILL after the save of this process's N-th keyframe (first start only).
  void kill_after_save_for_test(KeyframeId id, const MapChanges& changes);
  // The keyframe with its features on the mapper keyframes topic, for a frontend that rebuilds the
  // map from DDS (needs the camera, so only once the mapper runs).
  void publish_keyframe(const Keyframe& keyframe);
  // Ends a batch of states: the version markers of both state topics (messages::MirrorVersion).
  void write_version_markers(std::uint64_t map_version, std::uint64_t correction_id = 0);
  // KeyframeDone for a mapped keyframe, or (correction_id != 0) for an applied correction.
  void acknowledge(KeyframeId id, std::uint64_t correction_id = 0);
  void log_summary();

  // The inertial local BA (options_.inertial.enabled; docs/local_mapper.md, Inertial local BA).
  void configure_inertial();
  // Takes the IMU calibration, the stereo calibration (the IMU-camera extrinsic) and the readings that
  // arrived (never waits).
  void take_imu();
  // Lockstep: waits (at most imu.wait_s) until the IMU covers the keyframe's stamp; else the IMU is off.
  void wait_for_imu(std::int64_t stamp_ns, KeyframeId id);
  void report_inertial(const MapChanges& changes);

  void load_applied_corrections(const std::vector<std::string>& records);
  void remember_applied_correction(std::uint64_t id);

  MapperProcessOptions options_;
  std::unique_ptr<runtime::WaitSet> waitset_;
  // One writer each (runtime/checked_reader.hpp); samples are checked where they are converted, so a
  // bad keyframe of the frontend is still acknowledged.
  std::optional<runtime::CheckedReader<msg::Keyframe>> keyframe_reader_;
  std::optional<AgentKeyframeGuard> agent_guard_;  // --agents N > 1: several frontends (docs/agents.md)
  std::optional<runtime::CheckedReader<msg::LoopCorrection>> correction_reader_;
  std::optional<runtime::Writer<msg::KeyframeState>> keyframe_state_writer_;
  std::optional<runtime::Writer<msg::MapPointState>> point_state_writer_;
  std::optional<runtime::Writer<msg::KeyframeDone>> keyframe_done_writer_;
  // Every keyframe of the map with its features, once (topics().mapper_keyframes()).
  std::optional<runtime::Writer<msg::Keyframe>> mapper_keyframe_writer_;

  // A loaded map waits here for the first keyframe (which brings the camera the mapper needs).
  std::optional<MapSnapshot> loaded_;
  // The keyframes of the map loaded with --load-map (multi-session: old and new told apart at the end).
  std::set<KeyframeId> loaded_keyframe_ids_;
  std::unique_ptr<LocalMapper> mapper_;
  std::map<KeyframeId, PendingKeyframe> pending_;  // taken, not yet processed; id order
  std::map<std::uint64_t, LoopCorrection> pending_corrections_;
  std::set<std::uint64_t> applied_corrections_;  // ids; persisted in run_file_
  std::optional<runtime::RunJournal> run_file_;  // map_run_file_path(options_.map_file)
  int unsaved_keyframes_ = 0;
  MapChanges unsaved_changes_;               // merged since the last save: what the next record holds
  std::unique_ptr<MapJournal> map_journal_;  // options_.map_file's writer (map_journal.hpp)
  bool reader_wait_done_ = false;
  std::filesystem::path removed_file_;   // map_removed_path(options_.map_file); empty without a map file
  bool removed_file_holds_ids_ = false;  // false: nothing to clear before the next save that removes none
  int keyframes_mapped_here_ = 0;        // by this process (test.kill_after_saved_keyframes)
  MapSaveStats last_save_;
  // The map's size as last reported in the status (record(): counters MAP_added / MAP_removed).
  std::uint64_t reported_keyframes_ = 0;
  std::uint64_t reported_points_ = 0;

  std::optional<messages::ImuInput> imu_input_;
  std::unique_ptr<runtime::WaitSet> imu_waitset_;  // the IMU readers only: the lockstep wait
  std::unique_ptr<InertialMapping> inertial_;
  std::map<std::string, std::uint64_t> imu_counters_reported_;

  std::vector<msg::CovisibleKeyframe> covisible_buffer_;
  std::vector<msg::PointObservation> observation_buffer_;
};

}  // namespace heslam::local_mapper
