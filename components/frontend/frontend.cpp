// heslam-frontend's DDS side: readers, writers, lockstep acknowledgement, map-state mirroring.
#include "components/frontend/frontend.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <thread>
#include <utility>

#include "components/core/map/ids.hpp"
#include "components/core/mapping/map_file.hpp"
#include "components/core/place/vocabulary_setting.hpp"
#include "components/core/tracking/optimize_frame.hpp"
#include "components/core/tracking/pose_covariance.hpp"
#include "components/core/tracking/settings_file.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/keyframe.hpp"
#include "components/messages/odometry.hpp"
#include "components/messages/pose.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/run_id.hpp"
#include "runtime/run_journal.hpp"
#include "runtime/run_self.hpp"
#include "runtime/sequence.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::frontend {
namespace {

// Wait granularity of the main loop: shutdown is also signalled through the waitset, this only
// bounds how long a missed wake-up could delay it.
constexpr std::chrono::milliseconds kWaitPeriod{200};
// Before a calibration arrives, how often to look again while map states wait in their readers.
constexpr std::chrono::milliseconds kNoCalibrationPoll{5};
// How long a restarted frontend waits for the mapper's stored map state to start arriving, and then
// for the rest of it (one burst on loopback; a late state is applied with the next frame anyway).
constexpr std::chrono::milliseconds kMapHistoryWait{2000};
constexpr std::chrono::milliseconds kMapHistorySettle{100};
// A restarted frontend's ids start at restart << this (runtime::restart_number()): 2^40 ids per
// process, which no run exhausts, above every earlier process's.
constexpr int kRestartIdShift = 40;
// The publisher's rectified model and ours agree to this (both come from the same calibration; a
// larger difference means mismatched builds or a different rectification).
constexpr double kCameraTolerance = 1e-6;
// Frames / calibrations of a second writer kept in case it takes over (a restarted replay sends one
// frame, then waits for its acknowledgement); the image topic keeps 4 as well.
constexpr std::size_t kHeldFrames = 4;
constexpr std::size_t kHeldCalibrations = 4;
// KeyframeDone: how many acknowledgements of a restarted component are kept while the killed one
// still counts as matched.
constexpr std::size_t kMaxHeldKeyframeDone = 64;
// Counters of samples refused from the topics' writers or from other participants (log_rejections).
constexpr const char* kRejectionCounters[] = {
    "rejected_calibrations",       "refused_calibrations",  "rejected_keyframe_states", "rejected_points",
    runtime::kSecondWriterSamples, runtime::kSecondWriters, runtime::kOtherRunWriters};

bool same_camera(const PinholeStereo& a, const PinholeStereo& b) {
  return std::abs(a.fx_px - b.fx_px) < kCameraTolerance && std::abs(a.fy_px - b.fy_px) < kCameraTolerance &&
         std::abs(a.cx_px - b.cx_px) < kCameraTolerance && std::abs(a.cy_px - b.cy_px) < kCameraTolerance &&
         std::abs(a.baseline_m - b.baseline_m) < kCameraTolerance && a.width_px == b.width_px &&
         a.height_px == b.height_px;
}

// CPU time of the calling thread, in ms.
double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

// The wall clock DDS stamps samples with (SampleInfo::source_stamp_ns), in ns.
std::int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

// Peak resident set size of this process (VmHWM in /proc/self/status), in bytes; 0 if unknown.
std::uint64_t peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;  // reported in kB
  }
  return 0;
}

// One summary line per stage, in pipeline order: the per-frame breakdown of the run.
void log_stage_summary(const runtime::Logger& log, const runtime::Stats& stats) {
  static const char* const kOrder[] = {
      "rectify",        "he",    "extract", "stereo", "features", "track_initial", "track_local_map",
      "track_keyframe", "track", "imu",     "cpu",    "total",    "keyframe_wait"};
  const std::vector<runtime::StageSummary> stages = stats.stages();
  for (const char* name : kOrder) {
    for (const runtime::StageSummary& stage : stages) {
      if (stage.name != name) continue;
      std::ostringstream line;
      line << std::fixed << std::setprecision(2) << "stage " << std::left << std::setw(16) << stage.name << " median "
           << std::right << std::setw(7) << stage.p50_ms << " ms  p90 " << std::setw(7) << stage.p90_ms << " ms  max "
           << std::setw(7) << stage.max_ms << " ms  (" << stage.count
           << (stage.name == "keyframe_wait" ? " keyframes)" : " frames)");
      log.info(line.str());
    }
  }
  for (const runtime::StageSummary& stage : stages) {
    if (stage.name != "latency") continue;
    std::ostringstream line;
    line << std::fixed << std::setprecision(2) << "latency (frame published -> odometry) median " << stage.p50_ms
         << " ms  p99 " << stage.p99_ms << " ms  max " << stage.max_ms << " ms  (" << stage.count << " frames)";
    log.info(line.str());
  }
  log.info("peak RSS ", peak_resident_bytes() / (1024 * 1024), " MiB");
}

// The covariance of the last tracked frame's pose from its inliers of the last pose optimization
// (components/core/tracking/pose_covariance.hpp), for Odometry.T_wc_covariance; tracking does not use it.
std::optional<PoseCovariance> tracked_pose_covariance(const Tracker& tracker) {
  const Frame& frame = tracker.last_frame();
  return pose_covariance(tracker.camera(), frame_observations(frame, tracker.local_map()), frame.T_cw(),
                         tracker.options().disparity_sigma_ratio);
}

}  // namespace

Frontend::Frontend(const runtime::CommonArgs& args) : Component("frontend", args) {}

void Frontend::configure(const runtime::Config& config) {
  options_ = FrontendOptions::from_config(config, args().rest);
  // Frames on a shared-memory domain of their own (--image-transport shm) need a waitset across domains.
  waitset_ = std::make_unique<runtime::WaitSet>(participant(), image_participant().separate_domain()
                                                                   ? runtime::WaitScope::kAllDomains
                                                                   : runtime::WaitScope::kParticipant);
  calibration_reader_.emplace(participant(), topics().calibration(), log(), stats(),
                              messages::sample_check<msg::StereoCalibration>(),
                              messages::checked_options<msg::StereoCalibration>(kHeldCalibrations));
  // Frames are checked by process_frame (a bad frame of the replay is still acknowledged).
  runtime::CheckedReaderOptions frame_options;
  frame_options.rejected_counter = "bad_frames";
  frame_options.max_held = kHeldFrames;
  frame_reader_.emplace(image_participant().get(), topics().stereo(), log(), stats(), nullptr, frame_options);
  waitset_->attach(*calibration_reader_);
  waitset_->attach(*frame_reader_);
  if (options_.inertial.enabled) configure_inertial();
  if (options_.mapper_enabled) {
    keyframe_state_reader_.emplace(participant(), topics().keyframe_states(), log(), stats(),
                                   messages::sample_check<msg::KeyframeState>(),
                                   messages::checked_options<msg::KeyframeState>(messages::kMapStateHeld));
    point_state_reader_.emplace(participant(), topics().map_points(), log(), stats(),
                                messages::sample_check<msg::MapPointState>(),
                                messages::checked_options<msg::MapPointState>(messages::kMapStateHeld));
    keyframe_done_reader_.emplace(participant(), topics().keyframe_done());
    keyframe_done_roles_.emplace(log(), stats(), keyframe_done_reader_->name());
    waitset_->attach(*keyframe_state_reader_);
    waitset_->attach(*point_state_reader_);
    waitset_->attach(*keyframe_done_reader_);
  }
  odometry_writer_.emplace(participant(), topics().odometry());
  keyframe_writer_.emplace(participant(), topics().keyframes());
  frame_done_writer_.emplace(participant(), topics().frame_done());
  resume_from_journal();
  if (options_.session) configure_session();
  log().info("settings ",
             options_.settings_file.empty() ? std::string("(built-in defaults)") : options_.settings_file.string(),
             ": ", describe_settings(options_.features, options_.tracker));
  if (!options_.settings_unused_keys.empty()) {
    std::string keys;
    for (const std::string& key : options_.settings_unused_keys) keys += (keys.empty() ? "" : ", ") + key;
    log().warn("settings ", options_.settings_file.string(), ": not used by heslam: ", keys,
               " (docs/configuration.md, Settings file)");
  }
  log().info("HE ", to_string(options_.features.he.mode), ", ", options_.features.orb.features, " ORB features, ",
             options_.mapper_enabled ? "mirroring the local mapper's map" : "no local mapper (own map)",
             options_.wait_for_mapper ? ", lockstep waits for the mapper" : "",
             options_.loop_closers.empty() ? "" : " and " + options_.loop_closers.front(),
             options_.mapping ? "" : "; localization only: mapping off, no keyframe or point is created");
  std::error_code no_file;
  if ((options_.localize || options_.session) && !std::filesystem::exists(options_.mapper_map_file, no_file)) {
    // The mapper (started before us) writes the saved map there at its start: without it there is
    // nothing to localize in, and tracking would silently start a new map.
    throw std::runtime_error(
        std::string(options_.session ? "--session" : "--localize") + ": no saved map: the local mapper's map file " +
        options_.mapper_map_file.string() +
        (options_.saved_map.empty() ? std::string() : " (its copy of " + options_.saved_map.string() + ")") +
        " does not exist (start the mapper with --load-map FILE)");
  }
  if (options_.vocabulary) {
    log().info("vocabulary ", describe_vocabulary_setting(options_.vocabulary_file), ": ",
               options_.vocabulary->word_count(), " words; relocalization searches the whole map");
  } else {
    log().warn("vocabulary.file: none: no keyframe database, a lost frame is relocalized against the ",
               options_.tracker.relocalization_keyframes, " newest keyframes only");
  }
}

void Frontend::resume_from_journal() {
  stats().count(runtime::kOdometryFrames, 0);  // reported even when no frame arrives
  if (options_.journal_file.empty()) return;
  journal_.emplace(options_.journal_file);
  const OdometryJournal::Opened resumed = journal_->open_for_run(runtime::supervisor_run_id());
  if (resumed.dropped_lines > 0) {
    stats().count("journal_dropped_lines", resumed.dropped_lines);
    log().warn(resumed.dropped_report);
  }
  if (resumed.frames.empty()) return;
  last_seq_ = resumed.last_seq;
  for (const msg::Odometry& odometry : resumed.frames) {
    if (!last_seq_ || odometry.seq != *last_seq_) continue;  // the last finished frame
    if (odometry.state == heslam_msg_TRACKING_OK) {
      journal_last_pose_ = LastFramePose{odometry.reference_keyframe_id, messages::to_pose(odometry.T_ref_c),
                                         messages::to_pose(odometry.T_wc)};
    } else {
      journal_last_pose_.reset();  // lost then: relocalize
    }
  }
  // Into our transient-local history: a recorder restarted after the old process died (its history
  // with it) still gets every frame. A live recorder takes them again by seq, unchanged.
  for (const msg::Odometry& odometry : resumed.frames) odometry_writer_->write(odometry);
  stats().count("journal_frames", resumed.frames.size());
  stats().count(runtime::kOdometryFrames, resumed.frames.size());
  for (const msg::Odometry& odometry : resumed.frames) {
    if (!last_seq_ || odometry.seq > *last_seq_) resumed_unfinished_seqs_.insert(odometry.seq);
  }
  log().info("resuming after frame ", last_seq_ ? std::to_string(*last_seq_) : std::string("none"), ": ",
             resumed.frames.size(), " frames from ", journal_->path().string(),
             resumed.torn_lines > 0 ? " (" + std::to_string(resumed.torn_lines) + " torn lines skipped)" : "",
             "; their odometry published again");
}

void Frontend::run() {
  while (!shutdown_requested()) {
    const runtime::Wake wake = waitset_->wait(kWaitPeriod);
    if (wake == runtime::Wake::kShutdown) break;
    log().flush_throttled(/*due_only=*/true);
    take_calibration();
    take_imu();
    mirror_map_state();
    take_frames();
    // Map states wait in their readers until a calibration gives us a map to mirror them into;
    // their data-available status stays set meanwhile, so do not spin on it.
    if (!processor_ && wake == runtime::Wake::kData) std::this_thread::sleep_for(kNoCalibrationPoll);
  }
  count_frames_left();
  // Stopped, not killed: the run is over (or interrupted for good), nothing will resume from it.
  if (journal_) journal_->remove();
  log().flush_throttled();
  log_rejections();
  const auto counters = stats().counters();
  const auto count = [&](const char* name) { return counters.count(name) != 0 ? counters.at(name) : 0; };
  // The words of docs/outputs.md: untracked = processed without a pose (tracking lost or not
  // initialized); missed = published but never processed here. The run's "lost" is both.
  log().info("processed ", count("frames"), " frames (", count("untracked"), " untracked, of them ", count("lost"),
             " with tracking lost; ", count("bad_frames"), " bad), ", count("keyframes"), " keyframes");
  if (inertial_) {
    report_inertial();
    log().info(inertial_summary());
  }
  if (count("frames_already_processed") > 0) {
    log().info(count("frames_already_processed"),
               " frames published again were acknowledged without tracking them twice");
  }
  if (count("frames_missed") > 0) {
    log().warn(count("frames_missed"),
               " frames missed: published while this frontend was busy, only the newest kept (no pose: the run "
               "counts them as lost)");
  }
  if (count("frames_shed") > 0) {
    log().warn(count("frames_shed"), " frames shed: of the missed, skipped as older than ",
               options_.shedding.shed_after_ms, " ms with a newer frame waiting (realtime.shed_frames_after_ms); ",
               count("gap_predictions"), " frames after a gap started from the motion scaled to it");
  }
  if (count("poses_rechecked_after_gap") > 0 || count("poses_refused_after_gap") > 0) {
    log().warn(count("poses_rechecked_after_gap") + count("poses_refused_after_gap"),
               " frames after a gap had a doubtful first pose (docs/frontend.md, \"After a gap\"): ",
               count("poses_rechecked_after_gap"), " kept the best of every start, ", count("poses_refused_after_gap"),
               " refused (no pose)");
  }
  log_stage_summary(log(), stats());
  if (options_.localize && !relocalized_at_seq_) {
    // A localization run that never found itself in the map has no pose at all: a failure.
    throw std::runtime_error(never_relocalized_message(options_, count("frames")));
  }
}

void Frontend::take_calibration() {
  for (auto& received : calibration_reader_->take()) {
    if (!received.info.valid_data) continue;
    const msg::StereoCalibration& message = *received.sample;
    const PinholeStereo announced = messages::to_camera(message.rectified);
    if (processor_ && calibration_camera_ && same_camera(*calibration_camera_, announced)) continue;
    if (processor_ && received.info.publication_handle != calibration_writer_) {
      stats().count("refused_calibrations");
      log().error(
          "topic '", calibration_reader_->name(), "': refused a different calibration ('",
          runtime::to_string(message.source), "', fx ", announced.fx_px, " px, baseline ", announced.baseline_m,
          " m) from ", runtime::describe_writer(calibration_reader_->handle(), received.info.publication_handle),
          ": only the writer the run started with may change the calibration (counted as refused_calibrations)");
      continue;
    }
    try {
      const StereoCalibration calibration = messages::to_calibration(message);
      auto processor = std::make_unique<FrameProcessor>(calibration, options_);
      if (announced.fx_px > 0.0 && !same_camera(processor->camera(), announced)) {
        log().warn("calibration '", calibration.source, "': the publisher's rectified camera (fx ", announced.fx_px,
                   ", baseline ", announced.baseline_m, " m) differs from ours (fx ", processor->camera().fx_px,
                   ", baseline ", processor->camera().baseline_m, " m); using ours");
      }
      if (processor_) log().warn("calibration changed: tracking restarts with an empty map");
      processor_ = std::move(processor);
      if (inertial_) inertial_->set_camera(processor_->rectifier().T_B_rect());
      calibration_camera_ = announced;
      calibration_writer_ = received.info.publication_handle;
      if (options_.mapper_enabled) resume_in_mapper_map();
      const PinholeStereo& camera = processor_->camera();
      warn_if_settings_disagree(camera);
      log().info("calibration '", calibration.source, "': rectified ", camera.width_px, "x", camera.height_px, ", fx ",
                 camera.fx_px, " px, baseline ", camera.baseline_m, " m");
    } catch (const SavedMapCameraMismatch&) {
      throw;  // the run cannot go on in that map: the process ends with this line
    } catch (const std::exception& error) {
      stats().count("bad_calibrations");
      log().error(error.what());
    }
  }
}

void Frontend::warn_if_settings_disagree(const PinholeStereo& camera) {
  // The calibration comes with the data; a settings file written for another camera is named.
  constexpr double kTolerance = 0.01;
  const auto differs = [&](double settings, double calibration) {
    return settings > 0.0 && std::abs(settings - calibration) > kTolerance * calibration;
  };
  const double bf = camera.fx_px * camera.baseline_m;
  if (differs(options_.settings_camera_fx, camera.fx_px) || differs(options_.settings_camera_bf, bf)) {
    stats().count("settings_calibration_mismatches");
    log().warn("settings ", options_.settings_file.string(), ": Camera.fx ", options_.settings_camera_fx,
               " / Camera.bf ", options_.settings_camera_bf, " differ from the data's rectified calibration (fx ",
               camera.fx_px, " px, bf ", bf, "): the data's calibration is used (docs/configuration.md)");
  }
}

bool Frontend::mapper_map_file_of_this_run() const {
  std::error_code error_code;
  if (options_.mapper_map_file.empty() || !std::filesystem::exists(options_.mapper_map_file, error_code)) return false;
  // The mapper writes FILE.run (its supervisor's identity, which is ours) before its first map.
  return runtime::RunJournal::written_by_run(map_run_file_path(options_.mapper_map_file), runtime::supervisor_run_id(),
                                             kMapRunFileFormat);
}

void Frontend::resume_in_mapper_map() {
  // A restarted frontend: the mapper's map must be in the tracker before the first frame, or that
  // frame would start a second map.
  Tracker& tracker = processor_->tracker();
  // Ids of a restart start in a range of their own, whatever the files below still hold.
  if (const std::uint64_t restart = runtime::restart_number(); restart > 0) {
    tracker.skip_ids_through(restart << kRestartIdShift, restart << kRestartIdShift);
  }
  // The mapper's map file of this run exists at our start only after a restart, or when the mapper
  // started from a saved map (--load-map); on a fresh run it writes it after the first keyframe,
  // and the frontend starts before. It holds every keyframe the mapper acknowledged (saved before
  // each KeyframeDone), with features, which the state topics do not carry. It is loaded whether or
  // not the mapper runs now: killed together with us it is restarting, and its states (newer poses,
  // culls, merges) are applied as they arrive.
  const bool restarted = runtime::restart_number() > 0 || last_seq_.has_value();
  // One of several agents, started fresh: the mapper's file of this run can already hold the other
  // agents' keyframes (whether it does depends on which process started first), never ours. Resuming in
  // it made the run depend on that race; a fresh agent starts its own map, merged when a place of the
  // others' is recognised (docs/agents.md). Restarted, it resumes like a single agent.
  const bool fresh_agent = !restarted && !topics().agent_ns().empty();
  const bool take_file = !fresh_agent && mapper_map_file_of_this_run();
  bool loaded = false;
  if (take_file) {
    try {
      MapSnapshot snapshot = load_map_file(options_.mapper_map_file);
      if (!snapshot.journal.warning.empty()) log().warn(snapshot.journal.warning);
      check_saved_map_camera(snapshot);
      tracker.local_map() = std::move(snapshot.map);
      loaded = true;
    } catch (const SavedMapCameraMismatch&) {
      throw;
    } catch (const std::exception& error) {
      stats().count("unreadable_mapper_map_files");
      log().warn(error.what(), "; rebuilding the map from the local mapper's keyframes on DDS");
    }
  }
  // Without a usable file (unreadable, or on another host than the mapper), a restarted frontend
  // takes the mapper's live map from DDS: starting a new map would put a second map's keyframes
  // into the mapper's.
  if (!loaded && restarted) {
    tracker.local_map() = mapper_keyframes_from_dds();
    if (!tracker.local_map().keyframes.empty()) {
      stats().count("maps_from_dds");
      log().info("took ", tracker.local_map().keyframes.size(), " keyframes of the local mapper's map from DDS");
    } else {
      log().warn("restarted, but no map of this run's local mapper is readable (no file, nothing on ",
                 topics().mapper_keyframes().name, "); starting a new map");
    }
  }
  if (!take_file && !restarted) return;
  // States the mapper published already (it runs: only we were restarted) arrive shortly after the
  // readers match; wait briefly so the first frame is relocalized with the newest poses.
  if (keyframe_state_reader_->wait_for_writers(1, kMapHistoryWait)) {
    const auto deadline = std::chrono::steady_clock::now() + kMapHistoryWait;
    while (!keyframe_state_reader_->has_unread() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(kNoCalibrationPoll);
    }
    std::this_thread::sleep_for(kMapHistorySettle);
  }
  mirror_map_state();
  if (tracker.resume_in_map(journal_last_pose_)) {
    stats().count("resumed_in_map");
    log().info("resuming in the local mapper's map (", tracker.local_map().keyframes.size(), " keyframes, ",
               tracker.local_map().points.size(),
               " points): ", journal_last_pose_ ? "tracking on from the last journaled pose" : "relocalizing",
               " instead of starting a new map");
  }
}

Map Frontend::mapper_keyframes_from_dds() {
  Map map;
  // Created now and dropped after: transient-local history brings every keyframe the mapper holds,
  // which a reader kept all run long would hold twice over.
  runtime::CheckedReader<msg::Keyframe> reader(participant(), topics().mapper_keyframes(), log(), stats(),
                                               messages::sample_check<msg::Keyframe>(),
                                               messages::checked_options<msg::Keyframe>(messages::kMapStateHeld));
  if (!reader.wait_for_writers(1, kMapHistoryWait)) return map;
  // The history arrives after matching: taken until nothing new came for a settle period.
  const auto deadline = std::chrono::steady_clock::now() + kMapHistoryWait;
  auto quiet_since = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() < deadline) {
    bool any = false;
    for (auto& received : reader.take()) {
      if (!received.info.valid_data) continue;
      any = true;
      try {
        messages::DecodedKeyframe decoded = messages::to_keyframe(*received.sample);
        const KeyframeId id = decoded.keyframe.id;
        map.keyframes[id] = std::move(decoded.keyframe);
      } catch (const std::exception& error) {
        stats().count("bad_mapper_keyframes");
        log().warn_throttled("bad_mapper_keyframes", error.what());
      }
    }
    const auto now = std::chrono::steady_clock::now();
    if (any) quiet_since = now;
    if (!map.keyframes.empty() && now - quiet_since >= kMapHistorySettle) break;
    std::this_thread::sleep_for(kNoCalibrationPoll);
  }
  return map;
}

void Frontend::take_frames() {
  while (processor_ && !pending_.empty()) {  // frames that arrived before the calibration
    runtime::Received<msg::StereoFrame> frame = std::move(pending_.front());
    pending_.pop_front();
    process_frame(*frame.sample, frame.info.source_stamp_ns);
  }
  // Into one reused sample: a 722 KB pair per frame without an allocation (Reader::take_into).
  while (frame_reader_->take_into(frame_)) {
    if (!frame_.info.valid_data) continue;
    if (!processor_) {
      if (static_cast<int>(pending_.size()) >= options_.max_pending_frames) {
        stats().count("frames_dropped_before_calibration");
        pending_.pop_front();
      }
      pending_.push_back(std::exchange(frame_, runtime::Received<msg::StereoFrame>{}));
      continue;
    }
    // Before every frame, not only when run() wakes: a frontend slower than the camera finds the
    // next frame waiting every time and would otherwise never mirror the map while frames come (a
    // loop correction reached it only at the end of a loaded real-time run).
    mirror_map_state();
    if (shed_stale_frame()) continue;
    process_frame(*frame_.sample, frame_.info.source_stamp_ns);
    if (shutdown_requested()) return;
  }
}

bool Frontend::shed_stale_frame() {
  // Never the first frame: it starts the map, and a gap is counted as missed from the frame before it.
  if (options_.shedding.shed_after_ms <= 0.0 || !last_seq_ || frame_.info.source_stamp_ns <= 0 ||
      frame_.sample->seq <= *last_seq_) {
    return false;
  }
  const double age_ms = static_cast<double>(realtime_ns() - frame_.info.source_stamp_ns) * 1e-6;
  if (!shed_frame(options_.shedding, age_ms, frame_reader_->has_unread())) return false;
  // No pose: the next frame tracked counts it as missed by its seq jump (so processed + missed =
  // published still holds); shed says why (docs/outputs.md).
  stats().count("frames_shed");
  log().debug("frame ", frame_.sample->seq, ": shed (", age_ms, " ms old, a newer frame waiting)");
  return true;
}

void Frontend::count_frames_left() {
  const auto count = [&](std::uint64_t seq) {
    if (last_seq_ && seq <= *last_seq_) return;  // published again: processed already
    stats().count("frames_missed", last_seq_ ? seq - *last_seq_ : seq + 1);
    last_seq_ = seq;
  };
  for (const auto& frame : pending_) count(frame.sample->seq);
  pending_.clear();
  while (frame_reader_->take_into(frame_)) {
    if (frame_.info.valid_data) count(frame_.sample->seq);
  }
}

void Frontend::process_frame(const msg::StereoFrame& frame, std::int64_t published_ns) {
  if (last_seq_ && frame.seq <= *last_seq_) {
    // Published again (a publisher that restarted, or one re-sending for a restarted consumer): it
    // was tracked already; acknowledge so a lockstep publisher goes on, do not track it twice.
    stats().count("frames_already_processed");
    acknowledge(frame, nullptr);
    return;
  }
  // Checked before its seq counts: a malformed frame with a high seq must not make every later
  // frame look processed already.
  messages::GreyPair images;
  try {
    images = messages::to_grey_images(frame);
  } catch (const std::exception& error) {
    stats().count("bad_frames");
    log().warn_throttled("bad_frames", error.what());
    acknowledge(frame, nullptr);
    return;
  }
  if (last_seq_ && frame.seq > *last_seq_ + 1) stats().count("frames_missed", frame.seq - *last_seq_ - 1);
  // The source numbers its frames from 0: those before our first one were published while we were
  // not taking them yet (a loaded machine: start-up, or dropped before the calibration arrived).
  if (!last_seq_ && frame.seq > 0) stats().count("frames_missed", frame.seq);
  last_seq_ = frame.seq;
  FrameOutput output;
  double imu_cpu_ms = 0.0;
  if (inertial_) {
    wait_for_imu(frame);
    const double cpu_start_ms = thread_cpu_ms();
    predict_inertial(frame);
    imu_cpu_ms = thread_cpu_ms() - cpu_start_ms;
  }
  if (options_.shedding.frame_delay_ms > 0.0) {
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(options_.shedding.frame_delay_ms));
  }
  predict_over_gap(frame.seq);
  try {
    output = processor_->process(frame.stamp_ns, frame.seq, images.left, images.right);
  } catch (const std::exception& error) {
    // A bad frame is skipped and counted; it is still acknowledged so a lockstep run goes on.
    stats().count("bad_frames");
    log().warn_throttled("bad_frames", error.what());
    acknowledge(frame, nullptr);
    return;
  }
  const TrackResult& result = output.result;
  gap_prediction_.record(frame.seq, result.state == TrackingState::kOk, result.T_wc);
  stats().count("frames");
  if (options_.localize && !relocalized_at_seq_ && result.state == TrackingState::kOk) {
    relocalized_at_seq_ = frame.seq;
    log().info("relocalized in the saved map at frame ", frame.seq);
  }
  if (options_.session && !session_started_) follow_session_start(result, frame.seq);
  if (!result.pose_valid()) stats().count("untracked");
  if (result.state == TrackingState::kLost) stats().count("lost");
  // A frame after a gap whose first pose was doubtful (docs/frontend.md, "After a gap").
  if (result.gap_check == GapCheck::kChosen) stats().count("poses_rechecked_after_gap");
  if (result.gap_check == GapCheck::kRefused) stats().count("poses_refused_after_gap");
  if (result.motion == FrameMotion::kStill) stats().count("still_frames");
  if (result.motion == FrameMotion::kRotatingInPlace) stats().count("rotating_in_place_frames");
  for (const messages::StageTiming& timing : output.timings) stats().record_ms(timing.stage, timing.ms);

  if (result.new_keyframe) {
    stats().count("keyframes");
    const messages::KeyframeMessage keyframe(*result.new_keyframe, frame.seq, result.new_points, processor_->camera(),
                                             result.new_keyframe_reference, mirror_.version().complete());
    keyframe_writer_->write(keyframe.get());
    if (options_.mapper_enabled) {
      mirror_.own_keyframe(result.new_keyframe->id, result.new_keyframe_reference, mirror_.version().complete());
    }
  }
  follow_map_change(result, frame.seq);
  messages::OdometryMessage odometry(
      frame.stamp_ns, frame.seq, result, output.keypoints, output.timings, T_wo_,
      result.pose_valid() ? tracked_pose_covariance(processor_->tracker()) : std::nullopt);
  if (inertial_) {
    // The IMU's work for this frame (prediction, velocity, initialization), CPU time of this thread.
    const double cpu_start_ms = thread_cpu_ms();
    update_inertial(frame, result, odometry);
    stats().record_ms("imu", imu_cpu_ms + thread_cpu_ms() - cpu_start_ms);
  }
  // From the frame's publication (its writer's write time) to its odometry sample: the real-time
  // latency (docs/frontend.md, "Latency"); in lockstep it includes the replay's wait for the ack.
  if (published_ns > 0) stats().record_ms("latency", static_cast<double>(realtime_ns() - published_ns) * 1e-6);
  if (odometry_writer_->write(odometry.get()) == runtime::WriteResult::kTimeout) stats().count("odometry_timeouts");
  if (resumed_unfinished_seqs_.erase(frame.seq) == 0) stats().count(runtime::kOdometryFrames);
  if (journal_ && result.new_keyframe) journal_->append(odometry.get(), /*finished=*/false);
  log().debug("frame ", frame.seq, ": ", to_string(result.state), " (", to_string(result.method), "), ",
              result.tracked_points, " points, ", output.keypoints, " keypoints (", output.stereo_keypoints,
              " stereo), ", output.timings.back().ms, " ms");

  if (result.new_keyframe && options_.wait_for_mapper && !timed_wait_for_keyframe_done(result.new_keyframe->id)) {
    stats().count("mapper_timeouts");
    log().warn_throttled("mapper_timeouts", "keyframe ", format_id(result.new_keyframe->id),
                         ": no KeyframeDone from the mapper",
                         options_.loop_closers.empty() ? "" : " and the loop closer", " within ",
                         options_.mapper_timeout.count(), " ms; going on without it");
  }
  // Journaled before the acknowledgement: killed in between, the restarted process acknowledges
  // the frame the replay sends again instead of tracking it twice.
  if (journal_) journal_->append(odometry.get(), /*finished=*/true);
  acknowledge(frame, &output);
}

void Frontend::predict_over_gap(std::uint64_t seq) {
  // With an IMU its own prediction is better than a scaled motion model.
  if (!options_.shedding.predict_over_gaps || inertial_) return;
  Tracker& tracker = processor_->tracker();
  if (const std::optional<Pose3> T_wc = gap_prediction_.predict(seq, tracker.last_frame().T_wc)) {
    tracker.set_prediction(*T_wc);
    stats().count("gap_predictions");
  }
}

void Frontend::log_rejections() {
  const auto counters = stats().counters();
  std::ostringstream line;
  for (const char* name : kRejectionCounters) {
    const auto it = counters.find(name);
    if (it != counters.end() && it->second > 0) line << (line.tellp() > 0 ? ", " : "") << name << " " << it->second;
  }
  if (line.tellp() > 0) log().warn("samples refused from other writers or invalid: ", line.str());
}

void Frontend::mirror_map_state() {
  if (!options_.mapper_enabled) return;
  for (auto& received : keyframe_done_reader_->take()) {
    if (!received.info.valid_data) continue;
    // Another run's mapper on the domain must not acknowledge our keyframes.
    if (!runtime::writer_of_this_run(keyframe_done_reader_->handle(), received.info.publication_handle)) {
      stats().count(runtime::kOtherRunWriters);
      continue;
    }
    // Each component name is a role of its own (the mapper, each loop closer, awaited or not).
    const std::string component = received.sample->component == nullptr ? "" : received.sample->component;
    HeldKeyframeDone done{received.info.publication_handle,
                          component,
                          component,
                          received.sample->keyframe_id,
                          received.sample->map_version,
                          received.sample->correction_id};
    switch (keyframe_done_roles_->claim(keyframe_done_reader_->handle(), done.role, done.writer, done.subject())) {
      case runtime::RoleBinding::Claim::kAccepted: use_keyframe_done(done); break;
      case runtime::RoleBinding::Claim::kHeld:
        held_keyframe_done_.push_back(std::move(done));
        if (held_keyframe_done_.size() > kMaxHeldKeyframeDone) held_keyframe_done_.erase(held_keyframe_done_.begin());
        break;
      case runtime::RoleBinding::Claim::kRefused: break;
    }
  }
  for (auto held = held_keyframe_done_.begin(); held != held_keyframe_done_.end();) {
    const runtime::RoleBinding::Claim claim =
        keyframe_done_roles_->claim(keyframe_done_reader_->handle(), held->role, held->writer, held->subject(),
                                    /*again=*/true);
    if (claim == runtime::RoleBinding::Claim::kHeld) {
      ++held;
      continue;
    }
    if (claim == runtime::RoleBinding::Claim::kAccepted) use_keyframe_done(*held);
    held = held_keyframe_done_.erase(held);
  }
  // Without a processor there is no map to mirror into yet: the states stay in their readers
  // (keep-last per keyframe / point), so a restarted frontend still gets the whole map.
  if (!processor_) return;
  Map* map = &processor_->tracker().local_map();
  // Both readers are drained until empty before the version markers taken meanwhile count
  // (messages::MirrorVersion); the states wait in the mirror until their version is complete.
  for (bool drained = false; !drained;) {
    drained = true;
    for (auto& received : keyframe_state_reader_->take()) {
      drained = false;
      // Invalid-data samples (disposes, no-writer notices) carry no state: the mapper culls keyframes
      // by flag and its writers keep their instances when it exits or restarts.
      if (received.info.valid_data) mirror_.add(*received.sample);
    }
    for (auto& received : point_state_reader_->take()) {
      drained = false;
      if (!received.info.valid_data) {
        // Removed by the mapper, or its writer went away (then its restart republishes the point):
        // flag it culled, which the tracker skips and a later state revives.
        if (received.info.disposed) mirror_.dispose_point(received.sample->id);
        continue;
      }
      mirror_.add(*received.sample);
    }
  }
  const BatchedMirror::Applied applied = mirror_.apply(*map);
  // Ids of ours the mapper holds that this process did not make (its predecessor's): never again.
  Tracker& tracker = processor_->tracker();
  const std::uint8_t tag = tracker.options().id_tag;
  tracker.skip_ids_through(mirror_.largest_keyframe_counter(tag), mirror_.largest_point_counter(tag));
  if (applied.unknown_keyframe_states > 0) {
    stats().count("unknown_keyframe_states", static_cast<std::uint64_t>(applied.unknown_keyframe_states));
  }
  if (applied.correction) {
    // A loop correction's batch: keyframes we made meanwhile moved with their reference keyframe
    // (the mapper moves them alike), and the last frame follows its own (ORB-SLAM2's UpdateLastFrame),
    // so the motion model predicts the next frame in the corrected map.
    follow_loop_correction();
    stats().count("corrections_followed");
    stats().count("keyframes_moved_by_corrections", static_cast<std::uint64_t>(applied.keyframes_moved));
    log().info("loop correction in the mirror at map version ", mirror_.version().complete(), ": ",
               applied.keyframe_states, " keyframe and ", applied.point_states, " point states, ",
               applied.keyframes_moved, " of our keyframes in flight moved with their reference keyframe");
  }
}

void Frontend::follow_loop_correction() {
  Tracker& tracker = processor_->tracker();
  const Pose3 T_wc_before = tracker.last_frame().T_wc;
  tracker.follow_reference_keyframe();
  // The last frame's jump goes into odom -> world, so Odometry.T_oc continues without it (REP 105).
  const Pose3 T_corr = tracker.last_frame().T_wc * T_wc_before.inverse();
  T_wo_ = T_corr * T_wo_;
  // The inertial state (the recent frames' poses and velocities) follows the same jump.
  if (inertial_) inertial_->moved(T_corr);
}

void Frontend::use_keyframe_done(const HeldKeyframeDone& done) {
  // Acknowledgements this frontend never waits for are done with at once: a correction's, and another agent's
  // keyframe's (the topic is shared, docs/agents.md). A restarted mapper or loop closer acknowledges them again
  // (a replayed correction, each agent's last keyframe) within its predecessor's lease; remembered, that would
  // read as two live writers (runtime/role_binding.hpp) and fail the run.
  if (done.correction_id != 0 || agent_of(done.keyframe_id) != options_.agent)
    keyframe_done_roles_->done(done.subject());
  // The mapper's acknowledgement of a loop correction: the mirror acts on it when it applies the
  // correction's batch (whose version marker says the same, unless a newer marker replaced it).
  if (done.correction_id != 0) {
    if (processor_ && !mirror_.correction_acknowledged(done.map_version)) {
      // Applied already as an ordinary batch: our keyframes in flight were not moved (the mapper
      // still moves them, and their states bring them here), the last frame can still follow.
      follow_loop_correction();
      stats().count("corrections_seen_late");
    }
    return;
  }
  keyframes_done_[done.keyframe_id].insert(done.component);
  acknowledged_map_version_ = std::max(acknowledged_map_version_, done.map_version);
}

bool Frontend::timed_wait_for_keyframe_done(KeyframeId id) {
  // The lockstep handshake's wait per keyframe (the mapper's and the loop closers' work), wall time.
  auto timer = stats().time("keyframe_wait");
  return wait_for_keyframe_done(id);
}

bool Frontend::wait_for_keyframe_done(KeyframeId id) {
  const auto deadline = std::chrono::steady_clock::now() + options_.mapper_timeout;
  for (;;) {
    mirror_map_state();
    // The mapper publishes the keyframe's state before its KeyframeDone, but a loop closer's
    // acknowledgement may overtake the corrected states it waited for: wait for the map version too.
    if (keyframe_acknowledged(id) && mirror_.version().complete() >= acknowledged_map_version_) {
      keyframes_done_.erase(id);
      keyframe_done_roles_->done(id);
      mirror_map_state();
      return true;
    }
    // Two live writers acknowledged as one component (a forger, runtime/role_binding.hpp): the run
    // fails, and no acknowledgement (nor the map version it names) can be trusted to wait for.
    if (keyframe_done_roles_->conflicts() > 0) {
      keyframes_done_.erase(id);
      keyframe_done_roles_->done(id);
      stats().count("keyframes_not_awaited_after_conflict");
      return true;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline || shutdown_requested()) {
      keyframe_done_roles_->done(id);
      return false;
    }
    if (waitset_->wait(std::min<std::chrono::nanoseconds>(kWaitPeriod, deadline - now)) == runtime::Wake::kShutdown) {
      return false;
    }
  }
}

bool Frontend::keyframe_acknowledged(KeyframeId id) const {
  const auto it = keyframes_done_.find(id);
  if (it == keyframes_done_.end()) return false;
  // The mapper: any component that is not an awaited loop closer (its name is the pipeline's).
  bool mapper_done = false;
  for (const std::string& component : it->second) {
    if (std::find(options_.loop_closers.begin(), options_.loop_closers.end(), component) ==
        options_.loop_closers.end()) {
      mapper_done = true;
    }
  }
  if (!mapper_done) return false;
  for (const std::string& loop_closer : options_.loop_closers) {
    if (it->second.count(loop_closer) == 0) return false;
  }
  return true;
}

void Frontend::acknowledge(const msg::StereoFrame& frame, const FrameOutput* output) {
  msg::FrameDone done{};
  done.seq = frame.seq;
  done.stamp_ns = frame.stamp_ns;
  done.component = runtime::borrow(name());
  if (output != nullptr && output->result.new_keyframe) {
    done.keyframe_created = true;
    done.keyframe_id = output->result.new_keyframe->id;
  }
  frame_done_writer_->write(done);
}

void Frontend::configure_inertial() {
  imu_input_.emplace(participant(), topics(), log(), stats(), messages::ImuInput::Camera::kNotNeeded);
  imu_waitset_ = std::make_unique<runtime::WaitSet>(participant());
  imu_input_->attach(*imu_waitset_);
  inertial_ = std::make_unique<InertialFrontend>(options_.inertial, imu_input_->readings_topic());
  imu_input_->feed(inertial_->buffer());
  const InertialOptions& o = options_.inertial;
  log().info("inertial tracking: ", imu_input_->readings_topic(), " and ", imu_input_->calibration_topic(), ", ",
             o.lockstep
                 ? "lockstep (each frame waits for the IMU to cover it, at most " + std::to_string(o.wait_s) + " s)"
                 : std::string("real time (never waits for the IMU)"),
             ", initialization after ", o.init_min_keyframes, " keyframes over ", o.init_min_duration_s,
             " s, blackouts up to ", o.blackout_max_s, " s");
  stats().count("imu_readings", 0);
  stats().count("imu_bad_readings", 0);
  stats().count("imu_gaps", 0);
  stats().count("imu_initialized", 0);
  report_inertial();
}

void Frontend::take_imu() {
  if (!inertial_) return;
  imu_input_->take();
  if (!inertial_->has_calibration() && imu_input_->calibration()) {
    inertial_->set_imu_calibration(*imu_input_->calibration());
  }
}

void Frontend::wait_for_imu(const msg::StereoFrame& frame) {
  if (inertial_->off() || !options_.inertial.lockstep) return;
  const auto covered = [&] {
    return inertial_->has_calibration() &&
           inertial_->buffer().covered_until_ns() >= inertial_->imu_stamp(frame.stamp_ns);
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                               std::chrono::duration<double>(options_.inertial.wait_s));
  for (;;) {
    take_imu();
    if (covered()) return;
    if (imu_input_->ended()) {
      turn_inertial_off("the IMU stream ended (end_of_stream) before frame " + std::to_string(frame.seq) + " at " +
                        std::to_string(frame.stamp_ns) + " ns");
      return;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline || shutdown_requested()) {
      turn_inertial_off(std::string(inertial_->has_calibration()
                                        ? "no IMU readings on '" + imu_input_->readings_topic() + "'"
                                        : "no IMU calibration on '" + imu_input_->calibration_topic() + "'") +
                        " up to frame " + std::to_string(frame.seq) + " (" + std::to_string(frame.stamp_ns) +
                        " ns) within imu.wait_s " + std::to_string(options_.inertial.wait_s) + " s");
      return;
    }
    imu_waitset_->wait(std::min<std::chrono::nanoseconds>(kWaitPeriod, deadline - now));
  }
}

void Frontend::turn_inertial_off(const std::string& reason) {
  if (inertial_->off()) return;
  inertial_->turn_off(reason);
  stats().count("imu_off");
  log().warn("IMU off: ", reason, "; tracking goes on stereo-only");
  report_inertial();
}

void Frontend::predict_inertial(const msg::StereoFrame& frame) {
  take_imu();  // real time: whatever arrived (never waits)
  if (inertial_->off()) return;
  if (!inertial_->has_camera() || !inertial_->has_calibration()) return;
  const std::int64_t t = inertial_->imu_stamp(frame.stamp_ns);
  if (inertial_->buffer().dead_at(t)) {
    turn_inertial_off("no IMU reading on '" + imu_input_->readings_topic() + "' for " +
                      std::to_string(inertial_->buffer().options().dead_after_ns / 1'000'000) + " ms before frame " +
                      std::to_string(frame.seq) + " (" + std::to_string(frame.stamp_ns) + " ns): the IMU stopped");
    return;
  }
  const InertialFrontend::Prediction prediction = inertial_->predict(frame.stamp_ns);
  if (prediction.coverage == ImuCoverage::kDead) {
    turn_inertial_off(prediction.message);
    return;
  }
  if (!prediction.T_wc && !prediction.message.empty()) {
    stats().count("imu_frames_without_prediction");
    log().debug("frame ", frame.seq, ": no IMU prediction: ", prediction.message);
  }
  processor_->tracker().set_prediction(prediction.T_wc, prediction.fallback);
  processor_->tracker().set_inertial_constraint(prediction.constraint);
}

void Frontend::update_inertial(const msg::StereoFrame& frame, const TrackResult& result,
                               messages::OdometryMessage& odometry) {
  if (result.state == TrackingState::kInertialOnly) stats().count("inertial_only_frames");
  if (inertial_->off()) {
    report_inertial();
    return;
  }
  const InertialInitState before = inertial_->state();
  if (const std::optional<std::string> line =
          inertial_->update(frame.stamp_ns, result, processor_->tracker().local_map())) {
    if (inertial_->state() == InertialInitState::kInitialized) {
      if (!inertial_initialized_at_seq_) inertial_initialized_at_seq_ = frame.seq;
      log().info("frame ", frame.seq, ": ", *line);
    } else {
      log().warn_throttled("imu_init_failures", "frame ", frame.seq, ": ", *line);
    }
  }
  if (before != InertialInitState::kInitialized && inertial_->state() == InertialInitState::kInitialized) {
    stats().count("imu_initialized");
  }
  if (result.pose_valid()) {
    if (const std::optional<Eigen::Vector3d> v = inertial_->velocity()) odometry.set_velocity(*v);
    if (inertial_->estimate()) odometry.set_gravity(inertial_->estimate()->gravity_w);
  }
  report_inertial();
}

void Frontend::report_inertial() {
  const ImuBufferCounts& counts = inertial_->buffer().counts();
  const std::map<std::string, std::uint64_t> now = {
      {"imu_readings", counts.accepted},
      {"imu_bad_readings", counts.skipped()},
      {"imu_gaps", inertial_->gaps()},
      {"imu_pose_optimizations", inertial_->pose_optimizations()},
      {"imu_init_attempts", inertial_->init_attempts()},
  };
  for (const auto& [name, value] : now) {
    std::uint64_t& reported = imu_counters_reported_[name];
    if (value > reported) stats().count(name, value - reported);
    reported = std::max(reported, value);
  }
  status().set_message(inertial_summary());
}

std::string Frontend::inertial_summary() {
  const ImuBufferCounts& counts = inertial_->buffer().counts();
  std::ostringstream line;
  line << "IMU " << to_string(inertial_->state());
  if (inertial_->state() == InertialInitState::kInitialized && inertial_initialized_at_seq_) {
    line << " at frame " << *inertial_initialized_at_seq_;
  }
  if (!inertial_->reason().empty()) line << " (" << inertial_->reason() << ")";
  const auto counters = stats().counters();
  const auto count = [&](const char* name) { return counters.count(name) != 0 ? counters.at(name) : 0; };
  line << ": " << counts.accepted << " readings, " << counts.skipped() << " bad, " << inertial_->gaps() << " gaps, "
       << count("inertial_only_frames") << " inertial-only frames";
  return line.str();
}

void Frontend::follow_map_change(const TrackResult& result, std::uint64_t seq) {
  if (!result.pose_valid()) return;
  if (result.new_map) {
    stats().count("maps_started");
    const double lost_s = 1e-9 * static_cast<double>(result.new_map->lost_since_ns);
    log().info("new map ", result.map_id, " at frame ", seq, " (keyframe ", format_id(result.reference_kf),
               "): lost in map ", result.new_map->previous_map, " for ", result.new_map->lost_frames,
               " frames since stamp ", lost_s, " s, relocalization in every map failed (atlas.new_map_after_s ",
               options_.new_map_after_s, "); it starts at the last pose");
  }
  if (odometry_map_ && *odometry_map_ != result.map_id) {
    // Tracked on in another map without a relocalization or a new map: a merge renumbered ours, and
    // odom -> world took the merge's move when the frontend followed the correction (as a loop's).
    const bool merged = !result.new_map && result.method != TrackingMethod::kRelocalization;
    if (merged) {
      stats().count("maps_merged_into");
      log().info("frame ", seq, " in map ", result.map_id, ": map ", *odometry_map_, " was merged into it");
    } else if (!result.new_map) {
      stats().count("map_switches");
      log().info("frame ", seq, " relocalized in map ", result.map_id, " (tracked in map ", *odometry_map_,
                 " before the loss)");
    }
    // Each map has its own world: odom -> world takes the change, so Odometry.T_oc goes on from the last
    // odom pose instead of jumping with T_wc (REP 105, as at a loop correction). After a merge it has
    // already: taking it again would drop this frame's motion from the odometry.
    if (!merged) T_wo_ = result.T_wc * last_T_oc_.inverse();
  }
  odometry_map_ = result.map_id;
  last_T_oc_ = T_wo_.inverse() * result.T_wc;
}

// Multi-session mapping (docs/local_mapper.md): the start of a session on a saved map.
void Frontend::configure_session() {
  // A restarted frontend continues a session that started already: a loss from now on is an ordinary
  // one, the atlas's rule applies.
  if (last_seq_ || runtime::restart_number() > 0) {
    session_started_ = true;
    options_.tracker.new_map_after_ns = std::llround(options_.new_map_after_s * 1e9);
  }
  log().info("session on the saved map ",
             options_.saved_map.empty() ? options_.mapper_map_file.string() : options_.saved_map.string(),
             ": its first frames are relocalized in it; not relocalized within ", options_.session_new_map_after_s,
             " s (session.new_map_after_s), a new map starts and is merged into it when recognised");
}

void Frontend::follow_session_start(const TrackResult& result, std::uint64_t seq) {
  if (!result.pose_valid()) return;
  session_started_ = true;
  // From the first pose on, a loss is an ordinary one.
  processor_->tracker().set_new_map_after_ns(std::llround(options_.new_map_after_s * 1e9));
  const std::string saved =
      options_.saved_map.empty() ? options_.mapper_map_file.string() : options_.saved_map.string();
  if (result.new_map) {
    stats().count("session_new_maps");
    log().info("session: not relocalized in the saved map ", saved, " within ", options_.session_new_map_after_s,
               " s: new map ", result.map_id, " at frame ", seq,
               "; it is merged into the saved map when the loop closer recognises a place of it");
  } else {
    stats().count("session_relocalized");
    log().info("session: relocalized in the saved map ", saved, " at frame ", seq, " (map ", result.map_id, ")");
  }
}

void Frontend::check_saved_map_camera(const MapSnapshot& snapshot) const {
  // Only a saved map (session, localization) can be of another camera; a restart's file is this run's.
  if (!(options_.session || options_.localize) || !snapshot.camera) return;
  const PinholeStereo& camera = processor_->camera();
  if (same_map_camera(*snapshot.camera, camera)) return;
  const std::string saved =
      options_.saved_map.empty() ? options_.mapper_map_file.string() : options_.saved_map.string();
  throw SavedMapCameraMismatch("saved map " + saved + ": made with another camera (" +
                               describe_map_camera(*snapshot.camera) + ") than this run's calibration (" +
                               describe_map_camera(camera) + ")");
}

}  // namespace heslam::frontend
