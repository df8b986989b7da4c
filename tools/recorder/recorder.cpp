// heslam-recorder's DDS side and its output files, rewritten as frames arrive and finalized at shutdown.
#include "tools/recorder/recorder.hpp"

#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <thread>

#include <Eigen/Geometry>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/map_state.hpp"
#include "components/messages/pose.hpp"
#include "runtime/atomic_file.hpp"
#include "runtime/flags.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/run_id.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::recorder {
namespace {

constexpr std::chrono::milliseconds kWaitPeriod{200};
// At shutdown, samples still in flight from a frontend that just stopped: drain until the readers
// stay empty this long.
constexpr std::chrono::milliseconds kDrainQuietPeriod{300};
// At the end of a run, how long to wait for held samples: a frontend (or mapper) restarted after a
// kill -9 publishes while the killed one still counts as matched, until its DDS lease (2 s,
// config/cyclonedds.xml) expires; only then do its held samples take over. Within the supervisor's
// 5 s stop timeout.
constexpr std::chrono::milliseconds kHeldSamplesWait{2500};
// The files are rewritten whole (poses follow their keyframes' latest state), so the rewrites are
// spaced by this many times the duration of the last one: at most 1/21 (~5%) of a core however long
// the run, while a short run's files follow about every frame.
constexpr int kRewriteSpacingFactor = 20;
// At shutdown, the drain ends after this long even if samples keep arriving (a writer that never
// stops, e.g. a forger): within the supervisor's 5 s stop timeout, after kHeldSamplesWait.
constexpr std::chrono::milliseconds kMaxShutdownDrain{3500};
// The replay's count of published frames, on its status.
constexpr const char* kFramesPublishedCounter = "frames_published";
// Samples of a second writer kept in case it takes over (a restarted frontend within the 2 s lease
// of the dead one): the odometry history depth (docs/topics.md), and keyframes (~60 KB each).
constexpr std::size_t kHeldOdometry = 1200;
constexpr std::size_t kHeldKeyframes = 64;
// Counters of samples refused (invalid, or from a second writer), reported at exit.
constexpr const char* kRejectionCounters[] = {"rejected_odometry",        "rejected_keyframes",
                                              "rejected_keyframe_states", runtime::kSecondWriterSamples,
                                              runtime::kSecondWriters,    runtime::kOtherRunWriters};

// The field as its wire integer (runtime/wire_enum.hpp): a sample may hold a value of no enumerator.
const char* state_name(const heslam_msg_TrackingState& field) {
  switch (runtime::wire_value(field)) {
    case heslam_msg_TRACKING_OK: return "OK";
    case heslam_msg_TRACKING_LOST: return "LOST";
    case heslam_msg_TRACKING_INERTIAL_ONLY: return "INERTIAL_ONLY";
    case heslam_msg_TRACKING_NOT_INITIALIZED: return "NOT_INITIALIZED";
  }
  return "UNKNOWN";
}

eval::Format parse_format_or_throw(const std::string& text, const std::string& where) {
  const std::optional<eval::Format> format = eval::parse_format(text);
  if (!format) runtime::throw_bad_flag_value(where, "tum, kitti or euroc", text);
  return *format;
}

eval::PoseFrame parse_frame_or_throw(const std::string& text, const std::string& where) {
  const std::optional<eval::PoseFrame> frame = eval::parse_pose_frame(text);
  if (!frame) runtime::throw_bad_flag_value(where, "body, cam0 or rectified", text);
  return *frame;
}

}  // namespace

// A gravity estimate outside this range (m/s^2) is not one (the Earth's is 9.78..9.83).
constexpr double kMinGravityM_S2 = 5.0;
constexpr double kMaxGravityM_S2 = 15.0;

std::filesystem::path sibling_path(const std::filesystem::path& output, const std::string& suffix) {
  return output.parent_path() / (output.stem().string() + suffix);
}

RecorderOptions RecorderOptions::from(const runtime::Config& config, const std::vector<std::string>& flags) {
  RecorderOptions options;
  options.output = config.get_path("output", options.output);
  options.format = parse_format_or_throw(config.get_choice("format", "tum", {"tum", "kitti", "euroc"}), "format");
  options.keyframe_output = config.get_path("keyframe_output", {});
  options.lost_output = config.get_path("lost_output", {});
  options.inertial_output = config.get_path("inertial_output", {});
  options.maps_output = config.get_path("maps_output", {});
  if (config.has("frame")) {
    options.frame = parse_frame_or_throw(config.get_choice("frame", "body", {"body", "cam0", "rectified"}), "frame");
    options.frame_given = true;
  }
  runtime::Flags parser("heslam-recorder [options]");
  parser.path("--output", "FILE", &options.output, "the trajectory file (the config's output)")
      .custom("--format", "tum|kitti|euroc", "its format (the config's format)",
              [&options](const std::string& value) { options.format = parse_format_or_throw(value, "--format"); })
      .custom("--frame", "body|cam0|rectified", "the frame of the poses written (the config's frame)",
              [&options](const std::string& value) {
                options.frame = parse_frame_or_throw(value, "--frame");
                options.frame_given = true;
              })
      .path("--keyframes", "FILE", &options.keyframe_output, "the keyframe trajectory (the config's keyframe_output)")
      .path("--lost", "FILE", &options.lost_output, "the stamps of lost frames (the config's lost_output)")
      .path("--inertial", "FILE", &options.inertial_output,
            "inertial runs: the world's gravity alignment and the velocities (the config's inertial_output)")
      .path("--maps", "FILE", &options.maps_output,
            "runs with several maps (the atlas): the map of each pose (the config's maps_output)")
      .integer("--agent", "N", &options.agent, -1, kMaxAgentId,
               "several agents (docs/agents.md): record agent N's keyframes (-1: a single agent)")
      .text("--source", "NAME", &options.source, "the status name of the source of the frames (empty: any)");
  parser.parse(flags);
  if (options.output.empty()) throw std::runtime_error("--output: expected a file name");
  const std::string extension = options.format == eval::Format::euroc ? ".csv" : ".txt";
  if (options.keyframe_output.empty()) options.keyframe_output = sibling_path(options.output, ".keyframes" + extension);
  if (options.lost_output.empty()) options.lost_output = sibling_path(options.output, ".lost.txt");
  if (options.inertial_output.empty()) options.inertial_output = sibling_path(options.output, ".inertial.txt");
  if (options.maps_output.empty()) options.maps_output = sibling_path(options.output, ".maps.txt");
  return options;
}

namespace {

// Not fsynced: the outputs are written again as frames arrive, and the journal holds the frames.
constexpr bool kSyncOutputs = false;

// Writes `path` through write(temporary) and a rename (runtime/atomic_file.hpp): the file is always
// either the previous complete version or the new one.
template <typename Write>
void write_output(const std::filesystem::path& path, const std::string& what, Write&& write) {
  if (std::filesystem::is_directory(path)) {
    throw std::runtime_error(path.string() + ": is a folder; expected the file name of the " + what);
  }
  std::error_code error;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), error);
  if (error) {
    throw std::runtime_error(path.parent_path().string() + ": cannot create the folder of the " + what + " (" +
                             error.message() + ")");
  }
  try {
    runtime::replace_file(path, write, kSyncOutputs);
  } catch (const std::runtime_error& failure) {
    throw std::runtime_error("cannot write the " + what + ": " + failure.what());
  }
}

// The atlas (docs/outputs.md): which map each pose is in, when the run had several. A one-map run
// writes no such file (and removes a stale one of an earlier run with the same output).
void write_maps(const RecordedTrajectories& recording, const RecorderOptions& options) {
  if (!recording.several_maps()) {
    std::error_code ignored;
    std::filesystem::remove(options.maps_output, ignored);
    return;
  }
  write_output(options.maps_output, "map ids", [&](const std::filesystem::path& path) {
    std::ofstream out(path);
    out.precision(9);
    out << std::fixed;
    out << "# heslam map ids (docs/outputs.md): the map of each pose of the trajectory files; poses of different "
           "maps are in different world frames (each map's own) until the maps are merged\n"
        << "# trajectory " << options.output.string() << ": seq stamp_s map_id, one line per pose, in its order\n";
    for (std::size_t i = 0; i < recording.frame_maps.size(); ++i) {
      out << recording.frames.frame_ids[i] << " " << recording.frames.stamps_s[i] << " " << recording.frame_maps[i]
          << "\n";
    }
    out << "# keyframes " << options.keyframe_output.string() << ": keyframe frame_seq stamp_s map_id\n";
    for (std::size_t i = 0; i < recording.keyframe_maps.size(); ++i) {
      out << "keyframe " << recording.keyframes.frame_ids[i] << " " << recording.keyframes.stamps_s[i] << " "
          << recording.keyframe_maps[i] << "\n";
    }
    out.flush();
    if (!out) throw std::runtime_error("write error");
  });
}

}  // namespace

void write_recording(const RecordedTrajectories& recording, const RecorderOptions& options) {
  write_output(options.output, "trajectory", [&](const std::filesystem::path& path) {
    eval::write_trajectory(path, recording.frames, options.format);
  });
  write_output(options.keyframe_output, "keyframe trajectory", [&](const std::filesystem::path& path) {
    eval::write_trajectory(path, recording.keyframes, options.format);
  });
  write_output(options.lost_output, "list of untracked frames", [&](const std::filesystem::path& path) {
    std::ofstream lost(path);
    // docs/outputs.md: the untracked frames (processed without a pose). Missed frames (never
    // processed) have no odometry, so no line here; the summary's "lost" counts both.
    lost << "# untracked frames (processed, no pose; never interpolated): seq stamp_ns state. Frames the frontend "
            "missed are not listed (docs/outputs.md)\n";
    for (const LostFrame& frame : recording.lost)
      lost << frame.seq << " " << frame.stamp_ns << " " << frame.state << "\n";
    lost.flush();
    if (!lost) throw std::runtime_error("write error");
  });
  write_maps(recording, options);
  if (!recording.R_gw && recording.velocities.empty()) return;  // stereo-only: no such file
  write_output(options.inertial_output, "inertial outputs", [&](const std::filesystem::path& path) {
    std::ofstream out(path);
    out.precision(9);
    out << std::fixed;
    out << "# heslam inertial outputs (docs/outputs.md): the trajectory files' world and the IMU body's velocities\n";
    if (recording.R_gw) {
      const Eigen::Quaterniond q(*recording.R_gw);
      out << "# world: gravity-aligned (z up, the map's origin and heading); R_gw from the map's world, qx qy qz qw:\n"
          << "R_gw " << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n"
          << "# gravity in the map's world, m/s^2:\n"
          << "g_w " << recording.gravity_w->x() << " " << recording.gravity_w->y() << " " << recording.gravity_w->z()
          << "\n";
    } else {
      out << "# world: the trajectory files' (not gravity-aligned: no gravity recorded)\n";
    }
    out << "# seq stamp_s vx vy vz (m/s, in that world)\n";
    for (const FrameVelocity& v : recording.velocities) {
      out << v.seq << " " << v.stamp_s << " " << v.v_w.x() << " " << v.v_w.y() << " " << v.v_w.z() << "\n";
    }
    out.flush();
    if (!out) throw std::runtime_error("write error");
  });
}

void express_in_frame(RecordedTrajectories& recording, eval::PoseFrame frame, const Pose3& T_x_r) {
  for (eval::Trajectory* trajectory : {&recording.frames, &recording.keyframes}) {
    trajectory->frame = frame;
    if (frame == eval::PoseFrame::rectified) continue;
    for (Pose3& pose : trajectory->poses_wc) pose = eval::to_pose_frame(pose, T_x_r);
  }
}

std::string summary_line(const FrameAccount& account, const std::filesystem::path& output) {
  return "tracked " + std::to_string(account.with_pose) + "/" + std::to_string(account.published) + " frames, " +
         std::to_string(account.without_pose()) + " lost, trajectory " + output.string();
}

Recorder::Recorder(const runtime::CommonArgs& args) : Component("recorder", args) {}

void Recorder::configure(const runtime::Config& config) {
  options_ = RecorderOptions::from(config, args().rest);
  odometry_reader_.emplace(participant(), topics().odometry(), log(), stats(), messages::sample_check<msg::Odometry>(),
                           messages::checked_options<msg::Odometry>(kHeldOdometry));
  runtime::CheckedReaderOptions keyframe_options = messages::checked_options<msg::Keyframe>(kHeldKeyframes);
  // Several agents: one writer of map/keyframes per agent (the local mapper guards who writes what).
  if (options_.agent >= 0) keyframe_options.single_writer = false;
  recorder_.set_agent(options_.agent);
  keyframe_reader_.emplace(participant(), topics().keyframes(), log(), stats(), messages::sample_check<msg::Keyframe>(),
                           keyframe_options);
  keyframe_state_reader_.emplace(participant(), topics().keyframe_states(), log(), stats(),
                                 messages::sample_check<msg::KeyframeState>(),
                                 messages::checked_options<msg::KeyframeState>(messages::kMapStateHeld));
  status_reader_.emplace(participant(), topics().status());
  calibration_reader_.emplace(participant(), topics().calibration());
  waitset_ = std::make_unique<runtime::WaitSet>(participant());
  waitset_->attach(*odometry_reader_);
  waitset_->attach(*keyframe_reader_);
  waitset_->attach(*keyframe_state_reader_);
  waitset_->attach(*status_reader_);
  waitset_->attach(*calibration_reader_);
  if (options_.frame == eval::PoseFrame::rectified) T_frame_rect_ = Pose3::Identity();
  log().info("recording to ", options_.output.string(), " (", eval::format_name(options_.format), ", poses of the ",
             eval::pose_frame_name(options_.frame), " frame)");
  // A restart of this run (kill -9, crash) resumes with every frame recorded before; keyframes come
  // back on their own (transient-local), and odometry published while we were down is replayed to
  // us by the frontend's writer (transient-local, the last 100 frames).
  journal_.emplace(sibling_path(options_.output, ".journal"));
  const FrameJournal::Opened resumed = journal_->open_for_run(runtime::supervisor_run_id());
  for (const RecordedFrame& frame : resumed.frames) recorder_.add_frame(frame);
  if (resumed.dropped_lines > 0) {
    stats().count("journal_dropped_lines", resumed.dropped_lines);
    log().warn(resumed.dropped_report);
  }
  if (!resumed.frames.empty() || resumed.torn_lines > 0) {
    stats().count("journal_frames", resumed.frames.size());
    log().info("resuming: ", resumed.frames.size(), " frames from ", journal_->path().string(),
               resumed.torn_lines > 0 ? " (" + std::to_string(resumed.torn_lines) + " torn lines skipped)" : "");
  }
  // Written now: an output that cannot be written is a start-up error (one line, exit 1, not
  // restarted), not a surprise at the end of the run; and a resumed run's files are current again.
  write_files();
}

std::chrono::milliseconds Recorder::wait_period() const {
  if (!files_stale_) return kWaitPeriod;
  const auto until_due = std::chrono::ceil<std::chrono::milliseconds>(next_write_ - std::chrono::steady_clock::now());
  return std::clamp(until_due, std::chrono::milliseconds(0), kWaitPeriod);
}

void Recorder::run() {
  while (!shutdown_requested()) {
    if (waitset_->wait(wait_period()) == runtime::Wake::kShutdown) break;
    if (drain() > 0) files_stale_ = true;
    if (files_stale_ && std::chrono::steady_clock::now() >= next_write_) write_files();
  }
}

FrameAccount Recorder::write_files() {
  const auto start = std::chrono::steady_clock::now();
  RecordedTrajectories recording = recorder_.build();
  express_in_frame(recording, T_frame_rect_ ? options_.frame : eval::PoseFrame::rectified,
                   T_frame_rect_.value_or(Pose3::Identity()));
  align_to_gravity(recording, T_frame_rect_.value_or(Pose3::Identity()));
  write_recording(recording, options_);
  const FrameAccount account = recorder_.account(frames_published_);
  status().set_message(summary_line(account, options_.output));
  files_stale_ = false;
  const auto now = std::chrono::steady_clock::now();
  next_write_ = now + (now - start) * kRewriteSpacingFactor;
  stats().count("rewrites");
  return account;
}

void Recorder::take_inertial(const msg::Odometry& odometry, RecordedFrame& frame) {
  // Inertial tracking's velocity and gravity; a non-finite one (or a gravity far from the Earth's) is
  // skipped and counted, the frame's pose kept.
  const auto vector = [](const double(&v)[3]) { return Eigen::Vector3d(v[0], v[1], v[2]); };
  if (odometry.velocity_valid) {
    const Eigen::Vector3d v_w = vector(odometry.v_w);
    if (v_w.allFinite()) {
      frame.v_w = v_w;
    } else {
      stats().count("rejected_velocities");
      log().warn_throttled("rejected_velocities", "odometry frame ", odometry.seq, ": field 'v_w' is not finite");
    }
  }
  if (odometry.gravity_valid) {
    const Eigen::Vector3d g_w = vector(odometry.g_w);
    if (g_w.allFinite() && g_w.norm() > kMinGravityM_S2 && g_w.norm() < kMaxGravityM_S2) {
      frame.g_w = g_w;
    } else {
      stats().count("rejected_gravities");
      log().warn_throttled("rejected_gravities", "odometry frame ", odometry.seq, ": field 'g_w' (", g_w.transpose(),
                           ") is not a gravity (finite, ", kMinGravityM_S2, "..", kMaxGravityM_S2, " m/s^2)");
    }
  }
}

void Recorder::take_calibration() {
  for (auto& received : calibration_reader_->take()) {
    if (!received.info.valid_data || T_frame_rect_) continue;
    try {
      const StereoCalibration calibration = messages::to_calibration(*received.sample);
      // The frontend's own rectification (the same calibration, the same computation), hence its
      // rectified camera exactly.
      const Pose3 T_B_rect = StereoRectifier(calibration).T_B_rect();
      T_frame_rect_ =
          options_.frame == eval::PoseFrame::body ? T_B_rect : Pose3(calibration.left.T_BS.inverse() * T_B_rect);
      log().info("poses of the ", eval::pose_frame_name(options_.frame), " frame (calibration '", calibration.source,
                 "')");
    } catch (const std::exception& error) {
      stats().count("bad_calibrations");
      log().error("topic ", topics().calibration().name, ": ", error.what());
    }
  }
}

std::size_t Recorder::drain() {
  std::size_t taken = 0;
  if (calibration_reader_->has_unread()) {
    const bool had_frame = T_frame_rect_.has_value();
    take_calibration();
    if (!had_frame && T_frame_rect_) ++taken;  // every pose changes frame: the files are due
  }
  for (auto& received : status_reader_->take()) {
    if (!received.info.valid_data) continue;
    const msg::ComponentStatus& status = *received.sample;
    if (!options_.source.empty() && runtime::to_string(status.name) != options_.source) continue;
    for (std::uint32_t i = 0; i < status.counters._length; ++i) {
      const msg::Counter& counter = status.counters._buffer[i];
      if (runtime::to_string(counter.name) == kFramesPublishedCounter) {
        frames_published_ = std::max<std::uint64_t>(frames_published_, counter.value);
      }
    }
  }
  for (auto& received : keyframe_reader_->take()) {
    ++taken;
    if (!received.info.valid_data) continue;
    const msg::Keyframe& keyframe = *received.sample;
    if (options_.agent >= 0 && agent_of(keyframe.id) != options_.agent) continue;  // another agent's
    recorder_.add_keyframe(keyframe.id, keyframe.stamp_ns, keyframe.frame_seq, messages::to_pose(keyframe.T_wc));
    recorder_.set_keyframe_map(keyframe.id, keyframe.map_id);
    stats().count("keyframes");
  }
  for (auto& received : keyframe_state_reader_->take()) {
    ++taken;
    const msg::KeyframeState& state = *received.sample;
    // Invalid-data samples (disposes, no-writer notices) carry no state: the mapper culls keyframes
    // by flag and its writers keep their instances when it exits or restarts.
    if (!received.info.valid_data || messages::is_version_marker(state)) continue;
    recorder_.update_keyframe(state.id, messages::to_pose(state.T_wc), state.parent_id, state.culled);
    recorder_.set_keyframe_map(state.id, state.map_id);
  }
  for (auto& received : odometry_reader_->take()) {
    ++taken;
    if (!received.info.valid_data) continue;
    const msg::Odometry& odometry = *received.sample;
    RecordedFrame frame;
    frame.stamp_ns = odometry.stamp_ns;
    frame.seq = odometry.seq;
    // An inertial-only frame has a pose (the IMU's, vision could not track it): written, not lost.
    frame.tracked = runtime::wire_value(odometry.state) == heslam_msg_TRACKING_OK ||
                    runtime::wire_value(odometry.state) == heslam_msg_TRACKING_INERTIAL_ONLY;
    frame.state = state_name(odometry.state);
    frame.reference = odometry.reference_keyframe_id;
    frame.T_ref_c = messages::to_pose(odometry.T_ref_c);
    frame.T_wc = messages::to_pose(odometry.T_wc);
    frame.map_id = odometry.map_id;
    if (frame.tracked) take_inertial(odometry, frame);
    recorder_.add_frame(frame);
    if (odometry.keyframe_created && frame.tracked && frame.reference != kNoId) {
      recorder_.add_keyframe_frame(frame.reference, frame.stamp_ns, frame.seq, frame.T_wc);
    }
    journal_->append(frame);
    stats().count(frame.tracked ? "frames" : "frames_untracked");
    if (runtime::wire_value(odometry.state) == heslam_msg_TRACKING_INERTIAL_ONLY) stats().count("frames_inertial_only");
  }
  return taken;
}

void Recorder::on_shutdown() {
  const auto holding = [&] {
    return odometry_reader_->holds_samples() || keyframe_reader_->holds_samples() ||
           keyframe_state_reader_->holds_samples();
  };
  const auto held_deadline = std::chrono::steady_clock::now() + kHeldSamplesWait;
  const auto drain_deadline = std::chrono::steady_clock::now() + kMaxShutdownDrain;
  // Every writer gone (the supervisor stops the recorder after the frontend and the mapper): a
  // reliable writer is unmatched once its samples are acknowledged, so two more drains (one poll
  // apart, for a sample still on its way into the reader) take the last ones and no quiet period
  // needs waiting for.
  const auto writers_gone = [&] {
    return odometry_reader_->matched_writers() == 0 && keyframe_reader_->matched_writers() == 0 &&
           keyframe_state_reader_->matched_writers() == 0;
  };
  auto quiet_since = std::chrono::steady_clock::now();
  bool complete = false;
  int drains_since_gone = 0;
  while ((std::chrono::steady_clock::now() - quiet_since < kDrainQuietPeriod ||
          (holding() && std::chrono::steady_clock::now() < held_deadline)) &&
         std::chrono::steady_clock::now() < drain_deadline) {
    drains_since_gone = writers_gone() ? drains_since_gone + 1 : 0;
    if (drain() > 0) quiet_since = std::chrono::steady_clock::now();
    if (drains_since_gone >= 2 && !holding()) {
      complete = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!complete && std::chrono::steady_clock::now() - quiet_since < kDrainQuietPeriod) {
    stats().count("unfinished_drains");
    log().warn("samples kept arriving for ", kMaxShutdownDrain.count(),
               " ms after the run ended (a writer that does not stop); recording what arrived until then");
  }
  if (holding()) {
    log().warn("samples of a restarted frontend or mapper were still held back after ", kHeldSamplesWait.count(),
               " ms (its predecessor still counts as matched): they are not recorded");
  }
  const RecordedTrajectories recording = recorder_.build();
  const FrameAccount account = write_files();
  // Once, final: what the supervisor holds against the frontend's and the replay's counts.
  stats().count(runtime::kFramesRecorded, account.with_pose + account.untracked);
  stats().count(runtime::kFramesWithPose, account.with_pose);
  stats().count(runtime::kFramesAccounted, account.published);
  if (!T_frame_rect_) {
    log().warn("no camera calibration on ", topics().calibration().name,
               ": poses written in the rectified left camera "
               "frame (the files' header says so), not the ",
               eval::pose_frame_name(options_.frame), " frame");
  }
  journal_->remove();  // the outputs hold everything now
  if (recording.frames_without_reference > 0) {
    log().warn(recording.frames_without_reference,
               " frames referenced a keyframe that never arrived (odometry pose used)");
  }
  log().info("wrote ", recording.frames.size(), " poses to ", options_.output.string(), ", ",
             recording.keyframes.size(), " keyframes to ", options_.keyframe_output.string(), ", ",
             recording.lost.size(), " untracked frames to ", options_.lost_output.string());
  if (account.never_received_count() > 0) {
    log().warn(account.never_received_count(), " frames never reached the recorder (seq ",
               account.never_received_text(), "): missed by the frontend (its 'frames missed') or lost on the way");
  }
  const auto counters = stats().counters();
  std::string refused;
  for (const char* name : kRejectionCounters) {
    const auto it = counters.find(name);
    if (it != counters.end() && it->second > 0)
      refused += (refused.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(it->second);
  }
  if (!refused.empty()) log().warn("samples refused (invalid, or from a second writer; not recorded): ", refused);
  const std::string summary = summary_line(account, options_.output);
  // A run without a single pose is a failure, never a success with an empty file.
  if (account.with_pose == 0) throw std::runtime_error("no frame has a pose: " + summary);
  if (!T_frame_rect_ && options_.frame_given) {
    throw std::runtime_error(std::string("--frame ") + eval::pose_frame_name(options_.frame) +
                             ": no camera calibration arrived, the poses are of the rectified frame: " + summary);
  }
  status().set_state(runtime::ComponentState::kShuttingDown, summary);
  log().info(summary);
}

}  // namespace heslam::recorder
