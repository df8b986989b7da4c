// Parsing heslam-camera's command line (one clear line per bad option).
#include "tools/camera/camera_options.hpp"

#include <limits>
#include <stdexcept>

#include "runtime/flags.hpp"
#include "runtime/quote_value.hpp"

namespace heslam {

namespace {

// The documented range of each number (docs/tools/camera.md): beyond it a value is a typo.
constexpr double kMaxRate = 100.0;
constexpr double kMaxFps = 1000.0;
constexpr double kMaxToleranceMs = 1000.0;
constexpr double kMaxSeconds = 86400.0;

runtime::Flags camera_flags(CameraOptions& options) {
  runtime::Flags flags("heslam-camera SOURCE --calibration DIR|FILE [options]",
                       "  Publishes a live stereo camera (V4L2), a video file or an image folder on camera/stereo\n"
                       "  and camera/calibration, as heslam-replay does.");
  flags
      .choice("--layout", &options.layout,
              {{"auto", CameraLayout::kAuto},
               {"two-devices", CameraLayout::kTwoDevices},
               {"side-by-side", CameraLayout::kSideBySide}},
              "two-devices: SOURCE is LEFT,RIGHT or an EuRoC folder; side-by-side: one source whose\n"
              "frames hold left|right; auto (default): two-devices for LEFT,RIGHT or an EuRoC folder")
      .path("--calibration", "DIR|FILE", &options.calibration,
            "EuRoC mav0/ folder, Kalibr camchain YAML or ORB-SLAM2/3 stereo settings (required)")
      .number("--rate", "R", &options.rate, std::numeric_limits<double>::min(), kMaxRate,
              "recordings: speed, 1 = their own rate (default; a camera runs at its own)")
      .number("--fps", "F", &options.fps, 0.0, kMaxFps,
              "image folders without data.csv: their rate (0: the calibration's);\ndevices: the rate asked")
      .number("--pair-tolerance-ms", "MS", &options.pair_tolerance_ms, 0.0, kMaxToleranceMs,
              "two sources: how far a left and a right stamp may differ to pair (10)")
      .integer("--first-stamp-ns", "NS", &options.first_stamp_ns, std::int64_t{0},
               std::numeric_limits<std::int64_t>::max(),
               "video files, folders without data.csv: stamp of the first frame (0: steady clock)")
      .custom("--end", "finish|fail", "a recording's end: the run's end (finish) or a lost camera (fail)",
              [&options](const std::string& value) {
                if (value != "finish" && value != "fail") {
                  throw std::runtime_error("--end: expected finish or fail, got '" + runtime::quote_value(value) + "'");
                }
                options.end_is_failure = value == "fail";
              })
      .number("--wait", "S", &options.wait_subscriber_s, 0.0, kMaxSeconds,
              "wait up to S s for a frame subscriber before frame 0 (2)")
      .positional("SOURCE", "/dev/videoN or N, a video file, an image folder, or LEFT,RIGHT",
                  [&options](const std::string& arg) {
                    if (!options.source.empty()) {
                      throw std::runtime_error("'" + runtime::quote_value(arg) +
                                               "': unexpected second SOURCE argument (two sources: LEFT,RIGHT)");
                    }
                    options.source = arg;
                  });
  return flags;
}

}  // namespace

std::string camera_usage() {
  CameraOptions unused;
  return camera_flags(unused).usage();
}

CameraOptions parse_camera_options(const std::vector<std::string>& args) {
  CameraOptions options;
  runtime::Flags flags = camera_flags(options);
  flags.parse(args);
  if (options.source.empty()) throw std::runtime_error("missing SOURCE argument (see --help)");
  if (options.calibration.empty()) throw std::runtime_error("missing --calibration DIR|FILE (see --help)");
  return options;
}

}  // namespace heslam
