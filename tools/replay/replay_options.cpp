// Parsing heslam-replay's command line (one clear line per bad option).
#include "tools/replay/replay_options.hpp"

#include <stdexcept>

#include "runtime/flags.hpp"
#include "runtime/quote_value.hpp"

namespace heslam {

namespace {

// The documented range of each number (docs/tools.md): beyond it a value is a typo, and a huge one
// would overflow the durations made of it.
constexpr double kMaxRate = 100.0;        // x100 a camera's speed; 0 = as fast as possible
constexpr double kMaxSeconds = 86400.0;   // --ack-timeout, --wait: a day
constexpr double kMaxRecordingS = 1.0e6;  // --start-offset, --duration: 11 days of recording
constexpr double kMaxPreloadMb = 1.0e6;   // a terabyte

runtime::Flags replay_flags(ReplayOptions& options) {
  runtime::Flags flags("heslam-replay DATASET [options]",
                       "  Publishes an EuRoC ASL folder or a KITTI odometry sequence on camera/stereo and\n"
                       "  camera/calibration (and an EuRoC imu0/ on imu/readings, imu/calibration).");
  flags
      .custom("--format", "euroc|kitti|auto", "dataset layout (default auto)",
              [&options](const std::string& value) { options.format = parse_dataset_format(value); })
      .path("--camera", "FILE", &options.camera_file,
            "the calibration from this ORB-SLAM2/ORB-SLAM3 stereo settings file\n"
            "instead of the dataset's (empty: the dataset's)")
      .number("--rate", "R", &options.rate, 0.0, kMaxRate,
              "speed, 1 = real time (default), 0 = as fast as possible (0-100)")
      .toggle("--lockstep", &options.lockstep, "publish frame n+1 only after the consumer's FrameDone for frame n")
      .custom("--turns", "A,B,...",
              "lockstep with several agents: every agent's namespace, this one's among them;\n"
              "the frames of all are published one at a time in stamp order (docs/agents.md)",
              [&options](const std::string& value) {
                options.turns.clear();
                std::string::size_type start = 0;
                for (;;) {
                  const std::string::size_type comma = value.find(',', start);
                  const std::string name = value.substr(start, comma == std::string::npos ? comma : comma - start);
                  if (name.empty())
                    runtime::throw_bad_flag_value("--turns", "agent namespaces separated by ','", value);
                  options.turns.push_back(name);
                  if (comma == std::string::npos) break;
                  start = comma + 1;
                }
              })
      .number("--ack-timeout", "S", &options.ack_timeout_s, 0.001, kMaxSeconds,
              "lockstep: give up after S s without a consumer/FrameDone (10;\n0.001-86400)")
      .number("--wait", "S", &options.wait_subscriber_s, 0.0, kMaxSeconds,
              "wait up to S s for a frame subscriber before frame 0 (2; 0-86400)")
      .toggle("--loop", &options.loop, "start over at the end (stamps keep increasing)")
      .number("--start-offset", "S", &options.start_offset_s, 0.0, kMaxRecordingS,
              "skip the first S seconds of the recording (0-1e6)")
      .number("--duration", "S", &options.duration_s, 0.0, kMaxRecordingS, "replay only S seconds (0-1e6)")
      .toggle("--start-paused", &options.start_paused, "start paused (space on the TTY or SIGUSR2 resumes)")
      // The toggles as values, for pipeline files whose $(arg) gives on or off (docs/tools/replay.md).
      .on_off("--loop-mode", &options.loop, "on = --loop, off = no loop (default)")
      .on_off("--start-paused-mode", &options.start_paused, "on = --start-paused, off = start playing (default)")
      .custom("--imu", "auto|none", "auto (default): publish imu0/ on imu/readings when the dataset has it",
              [&options](const std::string& value) {
                if (value != "auto" && value != "none") {
                  throw std::runtime_error("--imu: expected auto or none, got '" + runtime::quote_value(value) + "'");
                }
                options.imu = value == "auto";
              })
      .toggle("--no-imu", &options.imu, "the same as --imu none: publish no IMU readings", false)
      .toggle("--strict", &options.strict, "stop at the first missing/corrupt image or unpaired row")
      .number("--preload", "MB", &options.preload_mb, 0.0, kMaxPreloadMb,
              "decode pairs before frame 0 while they fit in MB megabytes (0-1e6; 0 = off,\n"
              "default): no PNG decoding during the run, as from a live camera")
      .toggle("--no-progress", &options.progress, "no progress line, even on a terminal", false)
      .toggle("--no-keyboard", &options.keyboard, "do not read the terminal (space = pause)", false)
      .note("Pause/resume: space on the TTY, or SIGUSR1 (pause) / SIGUSR2 (resume).")
      .positional("DATASET", "", [&options](const std::string& arg) {
        if (!options.dataset.empty()) {
          throw std::runtime_error("'" + runtime::quote_value(arg) +
                                   "': unexpected second dataset argument (the first is '" +
                                   runtime::quote_value(options.dataset.string()) + "'; see --help)");
        }
        options.dataset = arg;
      });
  return flags;
}

}  // namespace

std::string replay_usage() {
  ReplayOptions unused;
  return replay_flags(unused).usage();
}

ReplayOptions parse_replay_options(const std::vector<std::string>& args) {
  ReplayOptions options;
  runtime::Flags flags = replay_flags(options);
  flags.parse(args);
  const bool rate_given = flags.given("--rate");
  if (options.dataset.empty()) throw std::runtime_error("missing DATASET argument (see --help)");
  if (options.lockstep && rate_given) {
    throw std::runtime_error("--rate and --lockstep exclude each other (lockstep is paced by the consumer)");
  }
  return options;
}

}  // namespace heslam
