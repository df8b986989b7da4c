// The IMU input every inertial component reads the same way (see imu_input.hpp).
#include "components/messages/imu_input.hpp"

#include <exception>
#include <utility>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"

namespace heslam::messages {
namespace {

runtime::CheckedReaderOptions counted_as(std::string rejected_counter) {
  runtime::CheckedReaderOptions options;
  options.rejected_counter = std::move(rejected_counter);
  return options;
}

}  // namespace

ImuInput::ImuInput(runtime::Participant& participant, const runtime::Topics& topics, const runtime::Logger& log,
                   runtime::Stats& stats, Camera camera)
    : log_(log),
      stats_(stats),
      readings_(participant, topics.imu(), log, stats, nullptr, counted_as("imu_rejected_batches")),
      calibration_(participant, topics.imu_calibration(), log, stats, nullptr,
                   counted_as("imu_rejected_calibrations")) {
  if (camera == Camera::kNeeded) {
    camera_.emplace(participant, topics.calibration(), log, stats, sample_check<msg::StereoCalibration>(),
                    checked_options<msg::StereoCalibration>(1));
  }
}

void ImuInput::feed(ImuBuffer& buffer) { stream_ = std::make_unique<ImuStreamReader>(buffer); }

void ImuInput::attach(runtime::WaitSet& waitset) {
  waitset.attach(readings_);
  waitset.attach(calibration_);
  if (camera_) waitset.attach(*camera_);
}

void ImuInput::take() {
  const auto bad_calibration = [&](const std::string& topic, const std::exception& error) {
    stats_.count("imu_bad_calibrations");
    log_.warn_throttled("imu_bad_calibrations", "topic '", topic, "': ", error.what());
  };
  if (camera_) {
    for (auto& received : camera_->take()) {
      if (!received.info.valid_data || T_B_rect_) continue;
      try {
        T_B_rect_ = StereoRectifier(to_calibration(*received.sample)).T_B_rect();
      } catch (const std::exception& error) {
        bad_calibration(camera_->name(), error);
      }
    }
  }
  for (auto& received : calibration_.take()) {
    if (!received.info.valid_data || calibration_value_) continue;
    try {
      calibration_value_ = to_imu_calibration(*received.sample);
      log_.info("IMU calibration '", calibration_value_->source, "': ", calibration_value_->rate_hz,
                " Hz, time offset ", calibration_value_->time_offset_ns, " ns");
    } catch (const std::exception& error) {
      bad_calibration(calibration_.name(), error);
    }
  }
  for (auto& received : readings_.take()) {
    if (!received.info.valid_data || !stream_) continue;
    const ImuBatchReport report = stream_->add(*received.sample);
    if (report.lost_readings > 0) stats_.count("imu_lost_readings", report.lost_readings);
    for (const std::string& warning : report.warnings) log_.warn_throttled("imu_readings", warning);
  }
}

}  // namespace heslam::messages
