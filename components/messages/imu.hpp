// IMU input on the wire: the readings in batches (imu/readings) and the IMU calibration
// (imu/calibration), as core types. The writer side builds the messages; the reader side checks a
// batch's continuity (seq, first_index) and feeds an ImuBuffer.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "components/core/imu/imu_buffer.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

// A msg::ImuBatch and the readings it points into (so neither copy nor move).
class ImuBatchMessage {
 public:
  ImuBatchMessage(std::span<const ImuSample> samples, std::uint64_t seq, std::uint64_t first_index,
                  std::int64_t watermark_ns, bool end_of_stream);
  ImuBatchMessage(const ImuBatchMessage&) = delete;
  ImuBatchMessage& operator=(const ImuBatchMessage&) = delete;

  const msg::ImuBatch& get() const { return message_; }

 private:
  std::vector<msg::ImuReading> readings_;
  msg::ImuBatch message_{};
};

std::vector<ImuSample> to_samples(const msg::ImuBatch& batch);

// A msg::ImuCalibration and its source string.
class ImuCalibrationMessage {
 public:
  explicit ImuCalibrationMessage(const ImuCalibration& calibration);
  ImuCalibrationMessage(const ImuCalibrationMessage&) = delete;
  ImuCalibrationMessage& operator=(const ImuCalibrationMessage&) = delete;

  const msg::ImuCalibration& get() const { return message_; }

 private:
  std::string source_;
  msg::ImuCalibration message_{};
};

// Throws std::runtime_error naming the calibration's source and the field when it is unusable
// (a noise figure not positive and finite, T_BS not rigid).
ImuCalibration to_imu_calibration(const msg::ImuCalibration& message);

// What one batch did to the stream, for the reader's counters and warnings.
struct ImuBatchReport {
  std::uint64_t lost_readings = 0;      // readings between the last batch and this one never received
  std::uint64_t repeated_readings = 0;  // readings of this batch already received (a batch sent again)
  std::size_t rejected = 0;             // readings the buffer skipped (ImuBuffer::counts says why)
  std::vector<std::string> warnings;    // one line each, naming the topic and the field
};

// The reader's side of imu/readings: feeds each batch to `buffer` in order, with its watermark.
class ImuStreamReader {
 public:
  explicit ImuStreamReader(ImuBuffer& buffer) : buffer_(buffer) {}

  ImuBatchReport add(const msg::ImuBatch& batch);

  bool ended() const { return ended_; }
  std::uint64_t lost_readings() const { return lost_readings_; }

 private:
  ImuBuffer& buffer_;
  std::uint64_t next_index_ = 0;
  bool started_ = false;
  bool ended_ = false;
  std::uint64_t lost_readings_ = 0;
};

}  // namespace heslam::messages
