// What every heslam subscriber checks before it uses a sample: finite numbers, consistent sizes,
// non-zero ids, enum values in range. The one place per topic type; readers pass these to
// runtime::CheckedReader (validation + one writer per topic), which drops a failing sample, counts it
// and prints a rate-limited warning naming the topic and the field. A sample that passes can still
// be wrong (a plausible but false pose); that is what the single-writer rule is for.
//
// Each check returns what is wrong (e.g. "T_wc.position_m[1] is nan") or nothing.
#pragma once

#include <optional>
#include <string>

#include "runtime/checked_reader.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

std::optional<std::string> check(const msg::Pose& pose, const char* field);
std::optional<std::string> check(const msg::StereoFrame& frame);  // sizes and encoding
std::optional<std::string> check(const msg::StereoCalibration& calibration);
std::optional<std::string> check(const msg::Odometry& odometry);
std::optional<std::string> check(const msg::Keyframe& keyframe);
// The version markers (id 0) pass: only their map version is read.
std::optional<std::string> check(const msg::KeyframeState& state);
std::optional<std::string> check(const msg::MapPointState& point);
std::optional<std::string> check(const msg::LoopCorrection& correction);

// The check of T as a runtime::SampleCheck, and the counter its rejections go to
// (rejected_keyframes, rejected_odometry, ...; docs/topics.md lists them).
template <typename T>
runtime::SampleCheck<T> sample_check() {
  return [](const T& sample) { return check(sample); };
}
const char* rejected_counter(const msg::StereoCalibration*);
const char* rejected_counter(const msg::Odometry*);
const char* rejected_counter(const msg::Keyframe*);
const char* rejected_counter(const msg::KeyframeState*);
const char* rejected_counter(const msg::MapPointState*);
const char* rejected_counter(const msg::LoopCorrection*);

// Options of a checked single-writer reader of T (max_held: samples kept for a take-over).
template <typename T>
runtime::CheckedReaderOptions checked_options(std::size_t max_held = 64) {
  runtime::CheckedReaderOptions options;
  options.rejected_counter = rejected_counter(static_cast<const T*>(nullptr));
  options.max_held = max_held;
  return options;
}

// A restarted local mapper republishes its whole map at once (the KITTI 00 map: 118,000 points),
// possibly while the dead one still counts as matched: map state readers hold this many for the
// take-over. It also bounds what a flooding second writer costs (~100 MB at worst).
inline constexpr std::size_t kMapStateHeld = 200000;

}  // namespace heslam::messages
