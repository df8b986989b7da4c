// heslam-replay's own command line: what to replay and how fast. The flags every tool shares
// (--domain, --namespace, ...) are parsed first by runtime::parse_common_args.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/dataset/stereo_dataset.hpp"

namespace heslam {

struct ReplayOptions {
  std::filesystem::path dataset;
  DatasetFormat format = DatasetFormat::kAuto;
  // --camera FILE: the calibration from this ORB-SLAM2 / ORB-SLAM3 settings file instead of the
  // dataset's (empty: the dataset's sensor.yaml / calib.txt).
  std::filesystem::path camera_file;
  double rate = 1.0;      // --rate: 1 = real time, 0 = as fast as the transport allows
  bool lockstep = false;  // --lockstep: frame n+1 after FrameDone(n)
  // --turns A,B,...: several agents in lockstep (docs/agents.md): the agent namespaces of every agent's
  // replay, this one's (--agent-namespace) among them; the frames of all go out one at a time in stamp
  // order (equal stamps: in this list's order), so the run is repeatable. Empty: this replay alone.
  std::vector<std::string> turns;
  bool loop = false;
  double start_offset_s = 0.0;
  double duration_s = 0.0;  // 0 = to the end
  bool start_paused = false;
  // --imu auto|none, --no-imu: publish the EuRoC imu0/ (readings and calibration) when the dataset
  // has one (auto, the default), or never.
  bool imu = true;
  bool strict = false;             // --strict: a bad image or unpaired row stops the replay
  double ack_timeout_s = 10.0;     // --ack-timeout: lockstep wait for a consumer / a FrameDone
  double wait_subscriber_s = 2.0;  // --wait: before frame 0, wait this long for a frame reader
  bool progress = true;            // --no-progress: no progress line even on a TTY
  bool keyboard = true;            // --no-keyboard: do not read the TTY (space = pause)
  // --preload MB: decode the pairs before frame 0 while they fit in MB megabytes (0 = off), so that
  // PNG decoding does not compete with the consumers for the cores during the run, as with a live
  // camera whose driver hands over decoded images (the whole-system benchmarks).
  double preload_mb = 0.0;
};

// args: what parse_common_args left. Throws std::runtime_error naming the option and what was expected.
ReplayOptions parse_replay_options(const std::vector<std::string>& args);

std::string replay_usage();

}  // namespace heslam
