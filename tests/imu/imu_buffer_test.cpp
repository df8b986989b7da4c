// ImuBuffer with known answers: readings at 200 Hz with values that are linear in time (so the
// interpolated ends are exact), and each kind of bad input: NaN, saturation, duplicate and
// out-of-order stamps, a gap over 50 ms, an IMU that stops mid-run.
#include "components/core/imu/imu_buffer.hpp"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace heslam {
namespace {

constexpr std::int64_t kPeriodNs = 5'000'000;  // 200 Hz

// A reading whose values are linear in the stamp: interpolation reproduces them exactly.
ImuSample reading(std::int64_t stamp_ns) {
  const double t = static_cast<double>(stamp_ns) * 1e-9;
  ImuSample sample;
  sample.stamp_ns = stamp_ns;
  sample.gyro_rad_s = Eigen::Vector3d(0.1 + t, -0.2 * t, 0.3);
  sample.accel_m_s2 = Eigen::Vector3d(t, 9.81, -2.0 * t);
  return sample;
}

ImuBuffer filled(std::int64_t from_ns, std::int64_t to_ns) {
  ImuBuffer buffer({.source = "test/imu"});
  for (std::int64_t stamp = from_ns; stamp <= to_ns; stamp += kPeriodNs)
    EXPECT_TRUE(buffer.add(reading(stamp)).accepted());
  return buffer;
}

TEST(ImuBuffer, IntervalHasTheInnerReadingsAndExactEnds) {
  const ImuBuffer buffer = filled(0, 200'000'000);
  // Frames between IMU stamps: 12.5 ms to 62.5 ms holds the readings at 15, 20, ..., 60 ms.
  const ImuInterval interval = buffer.interval(12'500'000, 62'500'000);
  ASSERT_EQ(interval.coverage, ImuCoverage::kComplete) << interval.message;
  ASSERT_EQ(interval.samples.size(), 12u);
  EXPECT_EQ(interval.samples.front().stamp_ns, 12'500'000);
  EXPECT_EQ(interval.samples[1].stamp_ns, 15'000'000);
  EXPECT_EQ(interval.samples.back().stamp_ns, 62'500'000);
  for (const ImuSample& sample : interval.samples) {
    const ImuSample expected = reading(sample.stamp_ns);
    EXPECT_LT((sample.gyro_rad_s - expected.gyro_rad_s).norm(), 1e-15);
    EXPECT_LT((sample.accel_m_s2 - expected.accel_m_s2).norm(), 1e-15);
  }
  EXPECT_EQ(interval.largest_gap_ns, kPeriodNs);
  // Ends on IMU stamps: no extra reading.
  EXPECT_EQ(buffer.interval(10'000'000, 20'000'000).samples.size(), 3u);
  // The interval feeds preintegrate() as it is.
  const ImuPreintegration pre = preintegrate(interval.samples, 12'500'000, 62'500'000);
  EXPECT_NEAR(pre.duration_s(), 0.05, 1e-12);
}

TEST(ImuBuffer, WatermarkDecidesPendingWithoutClocks) {
  ImuBuffer buffer = filled(0, 50'000'000);
  EXPECT_EQ(buffer.interval(10'000'000, 52'000'000).coverage, ImuCoverage::kPending);
  // The source says it sent everything up to 52 ms: the newest reading (50 ms) is held to the end.
  buffer.set_watermark(52'000'000);
  const ImuInterval held = buffer.interval(10'000'000, 52'000'000);
  ASSERT_EQ(held.coverage, ImuCoverage::kComplete) << held.message;
  EXPECT_EQ(held.samples.back().stamp_ns, 52'000'000);
  EXPECT_EQ(held.samples.back().gyro_rad_s, reading(50'000'000).gyro_rad_s);
  buffer.set_watermark(1);  // never moves back
  EXPECT_EQ(buffer.covered_until_ns(), 52'000'000);
  EXPECT_EQ(buffer.interval(-10'000'000, 20'000'000).coverage, ImuCoverage::kBeforeFirst);
}

TEST(ImuBuffer, BadReadingsAreCountedSkipsNamingTheField) {
  ImuBuffer buffer({.source = "heslam/imu/readings"});
  ASSERT_TRUE(buffer.add(reading(0)).accepted());
  ImuSample nan = reading(5'000'000);
  nan.gyro_rad_s[1] = std::numeric_limits<double>::quiet_NaN();
  const ImuAddResult nan_result = buffer.add(nan);
  EXPECT_EQ(nan_result.rejection, ImuRejection::kNonFinite);
  EXPECT_EQ(nan_result.message, "heslam/imu/readings: reading at 5000000 ns: gyro_rad_s[1] is nan (skipped, 1 so far)");
  ImuSample saturated = reading(5'000'000);
  saturated.accel_m_s2[2] = -176.5;
  const ImuAddResult saturated_result = buffer.add(saturated);
  EXPECT_EQ(saturated_result.rejection, ImuRejection::kSaturated);
  EXPECT_NE(saturated_result.message.find("accel_m_s2[2] = -176.5"), std::string::npos) << saturated_result.message;
  ASSERT_TRUE(buffer.add(reading(10'000'000)).accepted());
  const ImuAddResult duplicate = buffer.add(reading(10'000'000));
  EXPECT_EQ(duplicate.rejection, ImuRejection::kDuplicate);
  EXPECT_NE(duplicate.message.find("stamp_ns repeats"), std::string::npos);
  EXPECT_EQ(buffer.add(reading(7'000'000)).rejection, ImuRejection::kOutOfOrder);
  EXPECT_EQ(buffer.counts().accepted, 2u);
  EXPECT_EQ(buffer.counts().non_finite, 1u);
  EXPECT_EQ(buffer.counts().saturated, 1u);
  EXPECT_EQ(buffer.counts().duplicates, 1u);
  EXPECT_EQ(buffer.counts().out_of_order, 1u);
  EXPECT_EQ(buffer.counts().skipped(), 4u);
  // The skipped readings left a 10 ms step, well within the gap bound.
  EXPECT_EQ(buffer.interval(0, 10'000'000).coverage, ImuCoverage::kComplete);
}

TEST(ImuBuffer, GapOverFiftyMillisecondsMakesTheIntervalUnusable) {
  ImuBuffer buffer = filled(0, 100'000'000);
  for (std::int64_t stamp = 151'000'000; stamp <= 300'000'000; stamp += kPeriodNs) buffer.add(reading(stamp));
  const ImuInterval gap = buffer.interval(80'000'000, 200'000'000);
  EXPECT_EQ(gap.coverage, ImuCoverage::kGap);
  EXPECT_EQ(gap.largest_gap_ns, 51'000'000);
  EXPECT_EQ(gap.message,
            "test/imu: interval [80000000, 200000000] ns: readings 51.000000 ms apart (more than "
            "50.000000 ms)");
  EXPECT_TRUE(gap.samples.empty());
  // Exactly 50 ms is allowed; the intervals on either side are fine.
  ImuBuffer fifty = filled(0, 100'000'000);
  for (std::int64_t stamp = 150'000'000; stamp <= 200'000'000; stamp += kPeriodNs) fifty.add(reading(stamp));
  EXPECT_EQ(fifty.interval(90'000'000, 160'000'000).coverage, ImuCoverage::kComplete);
  EXPECT_EQ(buffer.interval(0, 100'000'000).coverage, ImuCoverage::kComplete);
  EXPECT_EQ(buffer.interval(160'000'000, 296'000'000).coverage, ImuCoverage::kComplete);
}

TEST(ImuBuffer, ImuThatStopsMidRunIsDeadOnceTheSourceCoversLaterStamps) {
  ImuBuffer buffer = filled(0, 1'000'000'000);
  EXPECT_FALSE(buffer.dead_at(1'000'000'000));
  // The replay keeps sending watermark-only batches with the frames: readings stopped at 1 s.
  buffer.set_watermark(1'400'000'000);
  EXPECT_FALSE(buffer.dead_at(1'400'000'000));  // 400 ms without a reading: a gap, not yet dead
  EXPECT_EQ(buffer.interval(1'350'000'000, 1'400'000'000).coverage, ImuCoverage::kGap);
  buffer.set_watermark(1'600'000'000);
  EXPECT_TRUE(buffer.dead_at(1'600'000'000));
  const ImuInterval dead = buffer.interval(1'550'000'000, 1'600'000'000);
  EXPECT_EQ(dead.coverage, ImuCoverage::kDead);
  EXPECT_EQ(dead.message, "test/imu: interval [1550000000, 1600000000] ns: IMU dead (no reading since 1000000000 ns)");
  EXPECT_FALSE(buffer.dead_at(2'000'000'000));  // not covered yet: pending, not dead
  // It comes back: alive again.
  buffer.add(reading(1'700'000'000));
  EXPECT_FALSE(buffer.dead_at(1'700'000'000));
}

TEST(ImuBuffer, DiscardKeepsWhatLaterIntervalsNeed) {
  ImuBuffer buffer = filled(0, 100'000'000);
  buffer.discard_before(42'000'000);
  EXPECT_EQ(buffer.size(), 13u);  // 40 ms .. 100 ms
  EXPECT_EQ(buffer.interval(42'000'000, 90'000'000).coverage, ImuCoverage::kComplete);
  EXPECT_EQ(buffer.interval(30'000'000, 90'000'000).coverage, ImuCoverage::kBeforeFirst);
  EXPECT_EQ(buffer.add(reading(100'000'000)).rejection, ImuRejection::kDuplicate);
}

}  // namespace
}  // namespace heslam
