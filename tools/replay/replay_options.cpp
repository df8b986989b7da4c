// Parsing heslam-replay's command line (one clear line per bad option).
#include "tools/replay/replay_options.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "runtime/quote_value.hpp"

namespace heslam {

namespace {

// The documented range of each number (docs/tools.md): beyond it a value is a typo, and a huge one
// would overflow the durations made of it.
constexpr double kMaxRate = 100.0;           // x100 a camera's speed; 0 = as fast as possible
constexpr double kMaxSeconds = 86400.0;      // --ack-timeout, --wait: a day
constexpr double kMaxRecordingS = 1.0e6;     // --start-offset, --duration: 11 days of recording
constexpr double kMaxPreloadMb = 1.0e6;      // a terabyte

double parse_double(const std::string& option, const std::string& text, double min_value, double max_value) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size() || !std::isfinite(value) || value < min_value ||
      value > max_value) {
    char range[64];
    std::snprintf(range, sizeof(range), "[%g, %g]", min_value, max_value);
    throw std::runtime_error(option + ": expected a number in " + range + ", got '" + runtime::quote_value(text) + "'");
  }
  return value;
}

}  // namespace

const char* replay_usage() {
  return "usage: heslam-replay DATASET [options]\n"
         "  Publishes an EuRoC ASL folder or a KITTI odometry sequence on camera/stereo and\n"
         "  camera/calibration.\n"
         "  --format euroc|kitti|auto   dataset layout (default auto)\n"
         "  --camera FILE               the calibration from this ORB-SLAM2/ORB-SLAM3 stereo settings file\n"
         "                              instead of the dataset's (empty: the dataset's)\n"
         "  --rate R                    speed, 1 = real time (default), 0 = as fast as possible (0-100)\n"
         "  --lockstep                  publish frame n+1 only after the consumer's FrameDone for frame n\n"
         "  --ack-timeout S             lockstep: give up after S s without a consumer/FrameDone (10;\n"
         "                              0.001-86400)\n"
         "  --wait S                    wait up to S s for a frame subscriber before frame 0 (2; 0-86400)\n"
         "  --loop                      start over at the end (stamps keep increasing)\n"
         "  --start-offset S            skip the first S seconds of the recording (0-1e6)\n"
         "  --duration S                replay only S seconds (0-1e6)\n"
         "  --start-paused              start paused (space on the TTY or SIGUSR2 resumes)\n"
         "  --strict                    stop at the first missing/corrupt image or unpaired row\n"
         "  --preload MB                decode pairs before frame 0 while they fit in MB megabytes (0-1e6; 0 = off,\n"
         "                              default): no PNG decoding during the run, as from a live camera\n"
         "  --no-progress, --no-keyboard\n"
         "  Pause/resume: space on the TTY, or SIGUSR1 (pause) / SIGUSR2 (resume).\n";
}

ReplayOptions parse_replay_options(const std::vector<std::string>& args) {
  ReplayOptions options;
  bool rate_given = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw std::runtime_error(arg + ": missing value");
      return args[++i];
    };
    if (arg == "--format") {
      options.format = parse_dataset_format(value());
    } else if (arg == "--camera") {
      options.camera_file = value();
    } else if (arg == "--rate") {
      options.rate = parse_double(arg, value(), 0.0, kMaxRate);
      rate_given = true;
    } else if (arg == "--lockstep") {
      options.lockstep = true;
    } else if (arg == "--ack-timeout") {
      options.ack_timeout_s = parse_double(arg, value(), 0.001, kMaxSeconds);
    } else if (arg == "--wait") {
      options.wait_subscriber_s = parse_double(arg, value(), 0.0, kMaxSeconds);
    } else if (arg == "--loop") {
      options.loop = true;
    } else if (arg == "--start-offset") {
      options.start_offset_s = parse_double(arg, value(), 0.0, kMaxRecordingS);
    } else if (arg == "--duration") {
      options.duration_s = parse_double(arg, value(), 0.0, kMaxRecordingS);
    } else if (arg == "--start-paused") {
      options.start_paused = true;
    } else if (arg == "--strict") {
      options.strict = true;
    } else if (arg == "--preload") {
      options.preload_mb = parse_double(arg, value(), 0.0, kMaxPreloadMb);
    } else if (arg == "--no-progress") {
      options.progress = false;
    } else if (arg == "--no-keyboard") {
      options.keyboard = false;
    } else if (!arg.empty() && arg.front() == '-') {
      throw std::runtime_error(runtime::quote_value(arg) + ": unknown option (see --help)");
    } else if (options.dataset.empty()) {
      options.dataset = arg;
    } else {
      throw std::runtime_error("'" + runtime::quote_value(arg) + "': unexpected second dataset argument (the first is '" +
                               runtime::quote_value(options.dataset.string()) + "'; see --help)");
    }
  }
  if (options.dataset.empty()) throw std::runtime_error("missing DATASET argument (see --help)");
  if (options.lockstep && rate_given) {
    throw std::runtime_error("--rate and --lockstep exclude each other (lockstep is paced by the consumer)");
  }
  return options;
}

}  // namespace heslam
