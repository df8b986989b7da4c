// The IMU readings a consumer (the frontend) has received, checked, and cut into the intervals
// between frames. DDS-free: the adapter (components/messages/imu.hpp) feeds it what the imu/readings
// topic delivers; tests feed it directly.
//
//   ImuBuffer buffer({.source = "heslam/imu/readings"});
//   buffer.add(sample);                      // a bad reading is skipped and counted; see ImuAddResult
//   buffer.set_watermark(batch_watermark);   // the source says: every reading up to here was sent
//   ImuInterval interval = buffer.interval(previous_frame_ns, frame_ns);
//   if (interval.coverage == ImuCoverage::kComplete) preintegrate(interval.samples, t0, t1, ...);
//
// Every decision depends on the stamps of the data only (never on a clock), so lockstep runs repeat.
#pragma once

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "components/core/imu/preintegration.hpp"

namespace heslam {

// What a consumer needs to know about the IMU besides its readings (EuRoC imu0/sensor.yaml).
struct ImuCalibration {
  ImuNoise noise;
  double rate_hz = 0.0;
  Pose3 T_BS = Pose3::Identity();   // IMU (sensor) -> body
  std::int64_t time_offset_ns = 0;  // t_imu = t_camera + time_offset_ns
  std::string source;               // the file(s) it came from
};

struct ImuBufferOptions {
  std::string source = "imu";  // names the stream (e.g. the topic) in every message
  // An interval with two consecutive readings further apart than this is unusable (issue 34's bound:
  // at 200 Hz, 10 readings lost in a row).
  std::int64_t max_gap_ns = 50'000'000;
  // No reading for this long before a stamp the source has covered: the IMU stopped (state "dead").
  std::int64_t dead_after_ns = 500'000'000;
  // A reading at or beyond these magnitudes is clipped by the sensor, not measured. Defaults: the
  // ADIS16448 of the EuRoC rig (+-1000 deg/s, +-18 g).
  double gyro_saturation_rad_s = 17.45;
  double accel_saturation_m_s2 = 176.5;
};

enum class ImuRejection { kNone, kNonFinite, kSaturated, kDuplicate, kOutOfOrder };
const char* to_string(ImuRejection rejection);

struct ImuAddResult {
  ImuRejection rejection = ImuRejection::kNone;
  // Empty when accepted; else one line naming the stream, the reading's stamp and the field, e.g.
  // "heslam/imu/readings: reading at 1403636580838555648 ns: gyro_rad_s[1] is nan (skipped)".
  std::string message;
  bool accepted() const { return rejection == ImuRejection::kNone; }
};

enum class ImuCoverage {
  kComplete,     // samples span [t0, t1] with no gap over max_gap_ns
  kPending,      // the source has not yet covered t1: add more readings / a later watermark
  kBeforeFirst,  // no reading at or before t0 (the stream started after t0)
  kGap,          // two consecutive readings in the interval are more than max_gap_ns apart
  kDead,         // the source covered t1 but sent no reading for dead_after_ns before it
};
const char* to_string(ImuCoverage coverage);

struct ImuInterval {
  ImuCoverage coverage = ImuCoverage::kPending;
  // kComplete only: the readings inside (t0, t1) with readings interpolated at t0 and t1 added, so
  // preintegrate(samples, t0, t1) integrates exactly the interval.
  std::vector<ImuSample> samples;
  std::int64_t largest_gap_ns = 0;  // between consecutive readings over the interval
  std::string message;              // why it is not complete (one line naming the stream), else empty
};

struct ImuBufferCounts {
  std::uint64_t accepted = 0;
  std::uint64_t non_finite = 0;
  std::uint64_t saturated = 0;
  std::uint64_t duplicates = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t skipped() const { return non_finite + saturated + duplicates + out_of_order; }
};

class ImuBuffer {
 public:
  explicit ImuBuffer(ImuBufferOptions options = {});

  // Keeps a finite, unsaturated reading whose stamp is after the last kept one; anything else is
  // skipped and counted, and the result says why.
  ImuAddResult add(const ImuSample& sample);

  // The source's promise that every reading with stamp <= stamp_ns has been delivered (ImuBatch's
  // watermark_ns). Never moves back. Without it, the buffer covers up to its newest reading.
  void set_watermark(std::int64_t stamp_ns);
  // The stamp up to which the buffer knows it has every reading (INT64_MIN before anything came).
  std::int64_t covered_until_ns() const;

  // The readings over [t0_ns, t1_ns] (t0 < t1) or why they cannot be had. When the source covered t1
  // but the newest reading is before t1 (within max_gap_ns), the newest reading is held to t1.
  ImuInterval interval(std::int64_t t0_ns, std::int64_t t1_ns) const;

  // The IMU stopped: the source covered stamp_ns but the newest reading is more than dead_after_ns
  // older. False before the first reading (intervals then say kBeforeFirst) and while pending.
  bool dead_at(std::int64_t stamp_ns) const;

  // Drops readings no longer needed for intervals starting at or after stamp_ns (keeps the last one
  // at or before it).
  void discard_before(std::int64_t stamp_ns);

  const ImuBufferCounts& counts() const { return counts_; }
  std::size_t size() const { return samples_.size(); }
  bool empty() const { return samples_.empty(); }
  const ImuBufferOptions& options() const { return options_; }

 private:
  ImuAddResult reject(ImuRejection rejection, const ImuSample& sample, const std::string& what);

  ImuBufferOptions options_;
  std::deque<ImuSample> samples_;  // strictly increasing stamps
  std::int64_t watermark_ns_;
  std::int64_t last_stamp_ns_;  // of the last kept reading, also after discard_before
  ImuBufferCounts counts_;
};

}  // namespace heslam
