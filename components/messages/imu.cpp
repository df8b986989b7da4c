// IMU batches and calibration <-> core types (see imu.hpp).
#include "components/messages/imu.hpp"

#include <cmath>
#include <stdexcept>

#include "runtime/sequence.hpp"

namespace heslam::messages {
namespace {

double positive(double value, const std::string& source, const char* field) {
  if (!std::isfinite(value) || !(value > 0.0)) {
    throw std::runtime_error("IMU calibration '" + source + "': " + field + " = " + std::to_string(value) +
                             ": expected a positive number");
  }
  return value;
}

}  // namespace

ImuBatchMessage::ImuBatchMessage(std::span<const ImuSample> samples, std::uint64_t seq, std::uint64_t first_index,
                                 std::int64_t watermark_ns, bool end_of_stream) {
  readings_.reserve(samples.size());
  for (const ImuSample& sample : samples) {
    msg::ImuReading reading{};
    reading.stamp_ns = sample.stamp_ns;
    for (int i = 0; i < 3; ++i) {
      reading.gyro_rad_s[i] = sample.gyro_rad_s[i];
      reading.accel_m_s2[i] = sample.accel_m_s2[i];
    }
    readings_.push_back(reading);
  }
  message_.schema_version = msg::kSchemaVersion;
  message_.seq = seq;
  message_.first_index = first_index;
  message_.watermark_ns = watermark_ns;
  message_.end_of_stream = end_of_stream;
  message_.readings._buffer = readings_.data();
  message_.readings._length = static_cast<std::uint32_t>(readings_.size());
  message_.readings._maximum = static_cast<std::uint32_t>(readings_.size());
  message_.readings._release = false;
}

std::vector<ImuSample> to_samples(const msg::ImuBatch& batch) {
  std::vector<ImuSample> samples;
  for (const msg::ImuReading& reading : runtime::view(batch.readings)) {
    ImuSample sample;
    sample.stamp_ns = reading.stamp_ns;
    sample.gyro_rad_s = Eigen::Vector3d(reading.gyro_rad_s[0], reading.gyro_rad_s[1], reading.gyro_rad_s[2]);
    sample.accel_m_s2 = Eigen::Vector3d(reading.accel_m_s2[0], reading.accel_m_s2[1], reading.accel_m_s2[2]);
    samples.push_back(sample);
  }
  return samples;
}

ImuCalibrationMessage::ImuCalibrationMessage(const ImuCalibration& calibration) : source_(calibration.source) {
  message_.schema_version = msg::kSchemaVersion;
  const Eigen::Matrix4d T = calibration.T_BS.matrix();
  for (int i = 0; i < 16; ++i) message_.T_BS[i] = T(i / 4, i % 4);
  message_.rate_hz = calibration.rate_hz;
  message_.gyroscope_noise_density = calibration.noise.gyro_noise_density;
  message_.gyroscope_random_walk = calibration.noise.gyro_random_walk;
  message_.accelerometer_noise_density = calibration.noise.accel_noise_density;
  message_.accelerometer_random_walk = calibration.noise.accel_random_walk;
  message_.time_offset_ns = calibration.time_offset_ns;
  message_.source = source_.data();
}

ImuCalibration to_imu_calibration(const msg::ImuCalibration& message) {
  ImuCalibration calibration;
  calibration.source = runtime::to_string(message.source);
  const std::string source = calibration.source.empty() ? "<unnamed>" : calibration.source;
  calibration.rate_hz = positive(message.rate_hz, source, "rate_hz");
  calibration.noise.gyro_noise_density = positive(message.gyroscope_noise_density, source, "gyroscope_noise_density");
  calibration.noise.gyro_random_walk = positive(message.gyroscope_random_walk, source, "gyroscope_random_walk");
  calibration.noise.accel_noise_density =
      positive(message.accelerometer_noise_density, source, "accelerometer_noise_density");
  calibration.noise.accel_random_walk =
      positive(message.accelerometer_random_walk, source, "accelerometer_random_walk");
  calibration.time_offset_ns = message.time_offset_ns;
  Eigen::Matrix4d T;
  for (int i = 0; i < 16; ++i) T(i / 4, i % 4) = message.T_BS[i];
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  if (!T.allFinite() || (R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6 || R.determinant() < 0.0 ||
      (T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 0.0) {
    throw std::runtime_error("IMU calibration '" + source + "': T_BS: expected a rigid transform");
  }
  calibration.T_BS.matrix() = T;
  return calibration;
}

ImuBatchReport ImuStreamReader::add(const msg::ImuBatch& batch) {
  ImuBatchReport report;
  const std::string& source = buffer_.options().source;
  if (batch.schema_version != msg::kSchemaVersion) {
    report.warnings.push_back(source + ": batch seq " + std::to_string(batch.seq) + ": schema_version " +
                              std::to_string(batch.schema_version) + ", expected " +
                              std::to_string(msg::kSchemaVersion) + " (skipped)");
    report.rejected = batch.readings._length;
    return report;
  }
  std::uint64_t skip = 0;
  if (started_ && batch.first_index > next_index_) {
    report.lost_readings = batch.first_index - next_index_;
    lost_readings_ += report.lost_readings;
    report.warnings.push_back(source + ": first_index " + std::to_string(batch.first_index) + ", expected " +
                              std::to_string(next_index_) + ": " + std::to_string(report.lost_readings) +
                              " readings lost");
  } else if (started_ && batch.first_index < next_index_) {
    skip = std::min<std::uint64_t>(next_index_ - batch.first_index, batch.readings._length);
    report.repeated_readings = skip;
  }
  started_ = true;
  const std::vector<ImuSample> samples = to_samples(batch);
  for (std::size_t i = static_cast<std::size_t>(skip); i < samples.size(); ++i) {
    const ImuAddResult result = buffer_.add(samples[i]);
    if (!result.accepted()) {
      ++report.rejected;
      report.warnings.push_back(result.message);
    }
  }
  next_index_ = std::max(next_index_, batch.first_index + batch.readings._length);
  buffer_.set_watermark(batch.watermark_ns);
  ended_ = ended_ || batch.end_of_stream;
  return report;
}

}  // namespace heslam::messages
