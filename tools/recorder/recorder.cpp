// heslam-recorder's DDS side and its output files.
#include "tools/recorder/recorder.hpp"

#include <fstream>
#include <stdexcept>
#include <thread>

#include "components/frontend/message_adapter.hpp"
#include "runtime/run_id.hpp"

namespace heslam::recorder {
namespace {

constexpr std::chrono::milliseconds kWaitPeriod{200};
// At shutdown, samples still in flight from a frontend that just stopped: drain until the readers
// stay empty this long.
constexpr std::chrono::milliseconds kDrainQuietPeriod{300};

const char* state_name(heslam_msg_TrackingState state) {
  switch (state) {
    case heslam_msg_TRACKING_OK: return "OK";
    case heslam_msg_TRACKING_LOST: return "LOST";
    case heslam_msg_TRACKING_NOT_INITIALIZED: return "NOT_INITIALIZED";
  }
  return "UNKNOWN";
}

eval::Format parse_format_or_throw(const std::string& text, const std::string& where) {
  const std::optional<eval::Format> format = eval::parse_format(text);
  if (!format) throw std::runtime_error(where + ": expected tum, kitti or euroc, got '" + text + "'");
  return *format;
}

}  // namespace

std::filesystem::path sibling_path(const std::filesystem::path& output, const std::string& suffix) {
  return output.parent_path() / (output.stem().string() + suffix);
}

RecorderOptions RecorderOptions::from(const runtime::Config& config, const std::vector<std::string>& flags) {
  RecorderOptions options;
  options.output = config.get_path("output", options.output);
  options.format = parse_format_or_throw(config.get_choice("format", "tum", {"tum", "kitti", "euroc"}), "format");
  options.keyframe_output = config.get_path("keyframe_output", {});
  options.lost_output = config.get_path("lost_output", {});
  for (std::size_t i = 0; i < flags.size(); ++i) {
    const std::string& flag = flags[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= flags.size()) throw std::runtime_error(flag + ": expected a value");
      return flags[++i];
    };
    if (flag == "--output") options.output = value();
    else if (flag == "--format") options.format = parse_format_or_throw(value(), "--format");
    else if (flag == "--keyframes") options.keyframe_output = value();
    else if (flag == "--lost") options.lost_output = value();
    else throw std::runtime_error("unexpected argument '" + flag + "' (see --help)");
  }
  if (options.output.empty()) throw std::runtime_error("--output: expected a file name");
  const std::string extension = options.format == eval::Format::euroc ? ".csv" : ".txt";
  if (options.keyframe_output.empty()) options.keyframe_output = sibling_path(options.output, ".keyframes" + extension);
  if (options.lost_output.empty()) options.lost_output = sibling_path(options.output, ".lost.txt");
  return options;
}

void write_recording(const RecordedTrajectories& recording, const RecorderOptions& options) {
  for (const auto& path : {options.output, options.keyframe_output, options.lost_output}) {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
  }
  eval::write_trajectory(options.output, recording.frames, options.format);
  eval::write_trajectory(options.keyframe_output, recording.keyframes, options.format);
  std::ofstream lost(options.lost_output);
  lost << "# frames without a pose (not tracked; never interpolated): seq stamp_ns state\n";
  for (const LostFrame& frame : recording.lost) lost << frame.seq << " " << frame.stamp_ns << " " << frame.state << "\n";
  if (!lost) throw std::runtime_error(options.lost_output.string() + ": cannot write");
}

Recorder::Recorder(const runtime::CommonArgs& args) : Component("recorder", args) {}

void Recorder::configure(const runtime::Config& config) {
  options_ = RecorderOptions::from(config, args().rest);
  odometry_reader_.emplace(participant(), topics().odometry());
  keyframe_reader_.emplace(participant(), topics().keyframes());
  keyframe_state_reader_.emplace(participant(), topics().keyframe_states());
  waitset_ = std::make_unique<runtime::WaitSet>(participant());
  waitset_->attach(*odometry_reader_);
  waitset_->attach(*keyframe_reader_);
  waitset_->attach(*keyframe_state_reader_);
  log().info("recording to ", options_.output.string(), " (", eval::format_name(options_.format), ")");
  // A restart of this run (kill -9, crash) resumes with every frame recorded before; keyframes come
  // back on their own (transient-local), and odometry published while we were down is replayed to
  // us by the frontend's writer (transient-local, the last 100 frames).
  journal_.emplace(sibling_path(options_.output, ".journal"));
  const FrameJournal::Opened resumed = journal_->open_for_run(runtime::supervisor_run_id());
  for (const RecordedFrame& frame : resumed.frames) recorder_.add_frame(frame);
  if (!resumed.frames.empty() || resumed.torn_lines > 0) {
    stats().count("journal_frames", resumed.frames.size());
    log().info("resuming: ", resumed.frames.size(), " frames from ", journal_->path().string(),
               resumed.torn_lines > 0 ? " (" + std::to_string(resumed.torn_lines) + " torn lines skipped)" : "");
  }
}

void Recorder::run() {
  while (!shutdown_requested()) {
    if (waitset_->wait(kWaitPeriod) == runtime::Wake::kShutdown) break;
    drain();
  }
}

std::size_t Recorder::drain() {
  std::size_t taken = 0;
  for (auto& received : keyframe_reader_->take()) {
    ++taken;
    if (!received.info.valid_data) continue;
    const msg::Keyframe& keyframe = *received.sample;
    recorder_.add_keyframe(keyframe.id, keyframe.stamp_ns, keyframe.frame_seq, frontend::to_pose(keyframe.T_wc));
    stats().count("keyframes");
  }
  for (auto& received : keyframe_state_reader_->take()) {
    ++taken;
    const msg::KeyframeState& state = *received.sample;
    // Invalid-data samples (disposes, no-writer notices) carry no state: the mapper culls keyframes
    // by flag and its writers keep their instances when it exits or restarts.
    if (!received.info.valid_data || frontend::is_version_marker(state)) continue;
    recorder_.update_keyframe(state.id, frontend::to_pose(state.T_wc), state.parent_id, state.culled);
  }
  for (auto& received : odometry_reader_->take()) {
    ++taken;
    if (!received.info.valid_data) continue;
    const msg::Odometry& odometry = *received.sample;
    RecordedFrame frame;
    frame.stamp_ns = odometry.stamp_ns;
    frame.seq = odometry.seq;
    frame.tracked = odometry.state == heslam_msg_TRACKING_OK;
    frame.state = state_name(odometry.state);
    frame.reference = odometry.reference_keyframe_id;
    frame.T_ref_c = frontend::to_pose(odometry.T_ref_c);
    frame.T_wc = frontend::to_pose(odometry.T_wc);
    recorder_.add_frame(frame);
    journal_->append(frame);
    stats().count(frame.tracked ? "frames" : "frames_untracked");
  }
  return taken;
}

void Recorder::on_shutdown() {
  auto quiet_since = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - quiet_since < kDrainQuietPeriod) {
    if (drain() > 0) quiet_since = std::chrono::steady_clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const RecordedTrajectories recording = recorder_.build();
  write_recording(recording, options_);
  journal_->remove();  // the outputs hold everything now
  if (recording.frames_without_reference > 0) {
    log().warn(recording.frames_without_reference, " frames referenced a keyframe that never arrived (odometry pose used)");
  }
  log().info("wrote ", recording.frames.size(), " poses to ", options_.output.string(), ", ", recording.keyframes.size(),
             " keyframes to ", options_.keyframe_output.string(), ", ", recording.lost.size(), " untracked frames to ",
             options_.lost_output.string());
}

}  // namespace heslam::recorder
