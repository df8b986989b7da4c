// Human-readable text of every project message for `heslam-spy echo`, YAML-like as `ros2 topic echo`.
// Summary mode (default) keeps large parts short: images become size, stamp and mean intensity;
// long sequences show their length and first elements. Full mode prints every element.
#pragma once

#include <string>

#include "components/core/map/ids.hpp"
#include "runtime/messages.hpp"
#include "runtime/sequence.hpp"

namespace heslam {

struct FormatOptions {
  bool full = false;  // --full: every element of every sequence, image bytes as hex rows
};

std::string format_message(const msg::StereoFrame& frame, const FormatOptions& options);
std::string format_message(const msg::StereoCalibration& calibration, const FormatOptions& options);
std::string format_message(const msg::ImuBatch& batch, const FormatOptions& options);
std::string format_message(const msg::ImuCalibration& calibration, const FormatOptions& options);
std::string format_message(const msg::Odometry& odometry, const FormatOptions& options);
std::string format_message(const msg::Keyframe& keyframe, const FormatOptions& options);
std::string format_message(const msg::KeyframeState& state, const FormatOptions& options);
std::string format_message(const msg::MapPointState& point, const FormatOptions& options);
std::string format_message(const msg::LoopCorrection& correction, const FormatOptions& options);
std::string format_message(const msg::FrameDone& done, const FormatOptions& options);
std::string format_message(const msg::KeyframeDone& done, const FormatOptions& options);
std::string format_message(const msg::ComponentStatus& status, const FormatOptions& options);
std::string format_message(const msg::OccupancyGrid2D& grid, const FormatOptions& options);
std::string format_message(const msg::DenseCloud& cloud, const FormatOptions& options);
std::string format_message(const msg::OccupancySaveRequest& request, const FormatOptions& options);
std::string format_message(const msg::OccupancySaveReply& reply, const FormatOptions& options);

// The line of a sample without data (its instance disposed, or its last writer gone), naming the
// instance by its key: only the key fields of such a sample are set. "# disposed: id lm:12",
// "# no writers any more: name frontend"; an unkeyed topic has one instance: no key.
template <typename T>
std::string format_instance_end(const T& sample, bool disposed) {
  std::string line = disposed ? "# disposed" : "# no writers any more";
  if constexpr (requires { sample.id; }) {
    line += ": id " + format_id(sample.id);
  } else if constexpr (requires { sample.name; }) {
    line += ": name " + runtime::to_string(sample.name);
  }
  return line + "\n";
}

// Mean of all bytes (0 for none): the image summary's intensity.
double mean_intensity(const msg::StereoFrame& frame, bool right);

}  // namespace heslam
