// The IMU input of an inertial component (frontend, local mapper, loop closer), read the same way by
// each: imu/readings fed in order into the component's ImuBuffer (lost readings counted as
// imu_lost_readings, a batch's warnings throttled as imu_readings), the first usable IMU calibration
// (imu/calibration) and, for a component that needs the camera-IMU geometry, the first usable stereo
// calibration's body-to-rectified-camera transform. A calibration that cannot be used is counted
// (imu_bad_calibrations) and named in a throttled warning; a later one is tried.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "components/core/geometry/pose.hpp"
#include "components/core/imu/imu_buffer.hpp"
#include "components/messages/imu.hpp"
#include "runtime/checked_reader.hpp"
#include "runtime/component.hpp"
#include "runtime/waitset.hpp"

namespace heslam::messages {

class ImuInput {
 public:
  enum class Camera { kNotNeeded, kNeeded };

  ImuInput(runtime::Participant& participant, const runtime::Topics& topics, const runtime::Logger& log,
           runtime::Stats& stats, Camera camera);

  // Where the readings go (owned by the caller, outliving this); set once, before the first take().
  void feed(ImuBuffer& buffer);
  // Wakes `waitset` when a reading or a calibration arrives.
  void attach(runtime::WaitSet& waitset);
  // Takes what has arrived (never waits).
  void take();

  const std::string& readings_topic() const { return readings_.name(); }
  const std::string& calibration_topic() const { return calibration_.name(); }
  // Empty without Camera::kNeeded.
  std::string camera_topic() const { return camera_ ? camera_->name() : std::string(); }

  const std::optional<ImuCalibration>& calibration() const { return calibration_value_; }
  // Rectified left camera -> body (StereoRectifier::T_B_rect); Camera::kNeeded only.
  const std::optional<Pose3>& T_B_rect() const { return T_B_rect_; }
  // The stream's last batch (end_of_stream) arrived.
  bool ended() const { return stream_ && stream_->ended(); }

 private:
  const runtime::Logger& log_;
  runtime::Stats& stats_;
  runtime::CheckedReader<msg::ImuBatch> readings_;
  runtime::CheckedReader<msg::ImuCalibration> calibration_;
  std::optional<runtime::CheckedReader<msg::StereoCalibration>> camera_;
  std::unique_ptr<ImuStreamReader> stream_;
  std::optional<ImuCalibration> calibration_value_;
  std::optional<Pose3> T_B_rect_;
};

}  // namespace heslam::messages
