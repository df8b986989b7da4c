// heslam-recorder: records odometry, keyframes and keyframe states, and keeps the full trajectory,
// the keyframe trajectory and the list of untracked frames on disk as it goes (each file replaced
// atomically, so it is always complete up to the last frame received), finalized at shutdown after
// draining its readers. Its status message and last line: "tracked N/M frames, K lost, trajectory FILE".
//
//   heslam-recorder [--output FILE] [--format tum|kitti|euroc] [--frame body|cam0|rectified]
//                   [--keyframes FILE] [--lost FILE]
//
// Config fields (same names): output, format, frame, keyframe_output, lost_output; flags win over them.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "runtime/checked_reader.hpp"
#include "runtime/component.hpp"
#include "tools/eval/trajectory_io.hpp"
#include "tools/recorder/frame_journal.hpp"
#include "tools/recorder/trajectory_recorder.hpp"

namespace heslam::recorder {

struct RecorderOptions {
  std::filesystem::path output = "trajectory.txt";
  eval::Format format = eval::Format::tum;
  std::filesystem::path keyframe_output;  // empty: <output stem>.keyframes<ext>
  std::filesystem::path lost_output;      // empty: <output stem>.lost.txt
  std::filesystem::path inertial_output;  // empty: <output stem>.inertial.txt (written by inertial runs only)
  std::filesystem::path maps_output;      // empty: <output stem>.maps.txt (written by runs with several maps only)
  // The frame the poses are written in (tools/eval/pose_frame.hpp), named in the files' header.
  // body: the calibration's T_BS body frame, what EuRoC's ground truth is of (= cam0 when T_BS is
  // the identity, as for KITTI).
  eval::PoseFrame frame = eval::PoseFrame::body;
  bool frame_given = false;  // set by --frame / `frame`: a run without a calibration then fails
  // --agent N (several agents, docs/agents.md): this recorder records agent N (its odometry comes on the
  // agent's topic, --agent-namespace); map/keyframes has one writer per agent, and the keyframe file
  // holds agent N's keyframes only. -1: a single agent, as before.
  int agent = -1;
  // --source NAME: the status name of the source whose frames_published counter says how many frames
  // were sent (several agents: each agent's replay); empty: any component's.
  std::string source;

  // Throws std::runtime_error naming the field or flag on a bad value.
  static RecorderOptions from(const runtime::Config& config, const std::vector<std::string>& flags);
};

// "<dir>/<stem><suffix>" next to output, e.g. traj.txt -> traj.keyframes.txt.
std::filesystem::path sibling_path(const std::filesystem::path& output, const std::string& suffix);

// Writes the three files, each to a temporary file beside it then renamed over it (a reader or a
// kill never sees a half-written file); creates the output folders. Throws std::runtime_error naming
// the file when it cannot be written (a folder, no permission, disk full).
void write_recording(const RecordedTrajectories& recording, const RecorderOptions& options);

// Rewrites the poses of `recording` (rectified left camera, world: it at the first keyframe) as poses
// of `frame`, given T_x_r (rectified camera -> that frame), and names the frame in both
// trajectories. Rectified: the poses are left untouched, bit for bit.
void express_in_frame(RecordedTrajectories& recording, eval::PoseFrame frame, const Pose3& T_x_r);

// "tracked N/M frames, K lost, trajectory FILE".
std::string summary_line(const FrameAccount& account, const std::filesystem::path& output);

class Recorder : public runtime::Component {
 public:
  explicit Recorder(const runtime::CommonArgs& args);
  // --check (heslam-supervisor --check): the flags and fields a run would refuse.
  static void check(const runtime::CommonArgs& args, const runtime::Config& config) {
    RecorderOptions::from(config, args.rest);
  }

 private:
  void configure(const runtime::Config& config) override;
  void run() override;
  void on_shutdown() override;
  bool accepts_positional_args() const override { return true; }
  // Takes everything the readers hold; returns the number of samples taken.
  std::size_t drain();
  void take_calibration();
  void take_inertial(const msg::Odometry& odometry, RecordedFrame& frame);
  // Rewrites the files from what is recorded and updates the status message with the summary.
  FrameAccount write_files();
  // How long the run loop may wait before the files are due again.
  std::chrono::milliseconds wait_period() const;

  RecorderOptions options_;
  TrajectoryRecorder recorder_;
  std::optional<FrameJournal> journal_;  // OUTPUT stem + .journal: survives a kill -9 of this process
  // Checked, one writer each (runtime/checked_reader.hpp): a NaN pose or a second frontend / mapper
  // on the domain never reaches the trajectory.
  std::optional<runtime::CheckedReader<msg::Odometry>> odometry_reader_;
  std::optional<runtime::CheckedReader<msg::Keyframe>> keyframe_reader_;
  std::optional<runtime::CheckedReader<msg::KeyframeState>> keyframe_state_reader_;
  std::optional<runtime::Reader<msg::ComponentStatus>> status_reader_;  // the replay's frames_published
  std::optional<runtime::Reader<msg::StereoCalibration>> calibration_reader_;
  // Rectified left camera -> options_.frame, from the calibration; unset until one arrives (the
  // files are then written in the rectified frame, and say so).
  std::optional<Pose3> T_frame_rect_;
  std::unique_ptr<runtime::WaitSet> waitset_;
  std::uint64_t frames_published_ = 0;  // the largest count any publisher reported
  bool files_stale_ = false;            // recorded data newer than the files
  std::chrono::steady_clock::time_point next_write_{};
};

}  // namespace heslam::recorder
