// The IMU messages: batch and calibration round trips, and the stream reader's continuity checks (a
// lost batch, a batch sent twice, a bad calibration field).
#include <limits>

#include <gtest/gtest.h>

#include "components/messages/imu.hpp"

namespace heslam::messages {
namespace {

std::vector<ImuSample> readings(std::int64_t from_ns, int count) {
  std::vector<ImuSample> samples;
  for (int i = 0; i < count; ++i) {
    ImuSample sample;
    sample.stamp_ns = from_ns + i * 5'000'000;
    sample.gyro_rad_s = Eigen::Vector3d(0.1 * i, -0.2, 0.3);
    sample.accel_m_s2 = Eigen::Vector3d(1.0, 9.81, -0.5 * i);
    samples.push_back(sample);
  }
  return samples;
}

TEST(ImuMessages, BatchRoundTrip) {
  const std::vector<ImuSample> samples = readings(1000, 4);
  const ImuBatchMessage message(samples, 7, 40, 16'000'000, false);
  EXPECT_EQ(message.get().seq, 7u);
  EXPECT_EQ(message.get().first_index, 40u);
  EXPECT_EQ(message.get().watermark_ns, 16'000'000);
  const std::vector<ImuSample> back = to_samples(message.get());
  ASSERT_EQ(back.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(back[i].stamp_ns, samples[i].stamp_ns);
    EXPECT_EQ(back[i].gyro_rad_s, samples[i].gyro_rad_s);
    EXPECT_EQ(back[i].accel_m_s2, samples[i].accel_m_s2);
  }
}

TEST(ImuMessages, CalibrationRoundTripAndBadField) {
  ImuCalibration calibration;
  calibration.rate_hz = 200.0;
  calibration.noise.accel_random_walk = 0.004;
  calibration.T_BS.translation() = Eigen::Vector3d(0.1, -0.2, 0.3);
  calibration.time_offset_ns = 1234;
  calibration.source = "imu0/sensor.yaml";
  const ImuCalibrationMessage message(calibration);
  const ImuCalibration back = to_imu_calibration(message.get());
  EXPECT_EQ(back.rate_hz, 200.0);
  EXPECT_EQ(back.noise.accel_random_walk, 0.004);
  EXPECT_EQ(back.noise.gyro_noise_density, calibration.noise.gyro_noise_density);
  EXPECT_EQ(back.T_BS.translation(), calibration.T_BS.translation());
  EXPECT_EQ(back.time_offset_ns, 1234);
  EXPECT_EQ(back.source, "imu0/sensor.yaml");
  msg::ImuCalibration bad = message.get();
  bad.gyroscope_noise_density = std::numeric_limits<double>::quiet_NaN();
  try {
    to_imu_calibration(bad);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(),
                 "IMU calibration 'imu0/sensor.yaml': gyroscope_noise_density = nan: expected a positive "
                 "number");
  }
  bad = message.get();
  bad.T_BS[0] = 2.0;
  EXPECT_THROW(to_imu_calibration(bad), std::runtime_error);
}

TEST(ImuMessages, StreamReaderCountsLostAndRepeatedReadings) {
  ImuBuffer buffer({.source = "heslam/imu/readings"});
  ImuStreamReader reader(buffer);
  const std::vector<ImuSample> all = readings(0, 30);
  const auto batch = [&](std::uint64_t seq, std::size_t first, std::size_t count, bool end = false) {
    const std::span<const ImuSample> part(all.data() + first, count);
    return ImuBatchMessage(part, seq, first, part.back().stamp_ns, end);
  };
  EXPECT_TRUE(reader.add(batch(0, 0, 10).get()).warnings.empty());
  EXPECT_EQ(buffer.covered_until_ns(), 45'000'000);
  // The same batch again (a republished one): its readings are not added twice, nothing is rejected.
  const ImuBatchReport repeated = reader.add(batch(0, 0, 10).get());
  EXPECT_EQ(repeated.repeated_readings, 10u);
  EXPECT_EQ(repeated.rejected, 0u);
  // Batch 1 (readings 10-19) lost: batch 2 says so.
  const ImuBatchReport lost = reader.add(batch(2, 20, 10, true).get());
  EXPECT_EQ(lost.lost_readings, 10u);
  ASSERT_EQ(lost.warnings.size(), 1u);
  EXPECT_EQ(lost.warnings[0], "heslam/imu/readings: first_index 20, expected 10: 10 readings lost");
  EXPECT_TRUE(reader.ended());
  EXPECT_EQ(buffer.counts().accepted, 20u);
  EXPECT_EQ(buffer.interval(40'000'000, 110'000'000).coverage, ImuCoverage::kGap);
}

}  // namespace
}  // namespace heslam::messages
