// heslam-camera's own command line: the source, its layout, the calibration, the pacing of recordings.
// The flags every tool shares (--domain, --namespace, ...) are parsed first by runtime::parse_common_args.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "tools/camera/stereo_capture.hpp"

namespace heslam {

struct CameraOptions {
  std::string source;  // a device, a video file, an image folder; "LEFT,RIGHT" for two
  CameraLayout layout = CameraLayout::kAuto;
  std::filesystem::path calibration;  // --calibration: EuRoC folder, Kalibr camchain, ORB-SLAM settings
  double rate = 1.0;                  // --rate: recordings only; 1 = the recording's own rate
  double fps = 0.0;                   // --fps: plain image folders; devices: the rate asked (0: theirs)
  double pair_tolerance_ms = 10.0;    // --pair-tolerance-ms: two sources, |left - right| stamps
  std::int64_t first_stamp_ns = 0;    // --first-stamp-ns: unstamped recordings (0: the steady clock)
  // --end fail: the end of a recording counts as a camera that disappeared (exit 1), as a device's
  // end always does; finish (the default): a recording's end is the end of the run (exit 0).
  bool end_is_failure = false;
  double wait_subscriber_s = 2.0;  // --wait: before frame 0, wait this long for a frame reader
};

// args: what parse_common_args left. Throws std::runtime_error naming the option and what was expected.
CameraOptions parse_camera_options(const std::vector<std::string>& args);

std::string camera_usage();

}  // namespace heslam
