// The IMU of an EuRoC ASL recording: mav0/imu0/data.csv (`#timestamp [ns], w_RS_S x y z [rad/s],
// a_RS_S x y z [m/s^2]`) and imu0/sensor.yaml (T_BS, rate_hz and the Kalibr noise model). DDS-free:
// the replay publishes it, tests and benchmarks read it directly.
#pragma once

#include <filesystem>
#include <vector>

#include <opencv2/core/persistence.hpp>

#include "components/core/geometry/pose.hpp"
#include "components/core/imu/preintegration.hpp"

namespace heslam {

struct ImuRecording {
  std::vector<ImuSample> samples;  // strictly increasing stamps
  ImuNoise noise;
  double rate_hz = 0.0;
  Pose3 T_BS = Pose3::Identity();  // IMU (sensor) -> body; EuRoC: the identity, the IMU is the body
  std::filesystem::path source;    // the data.csv read
};

// True when the dataset folder (or its mav0/) has an imu0/data.csv.
bool has_euroc_imu(const std::filesystem::path& dataset);

// The one reader of an IMU noise model (the replay's sensor.yaml and heslam-ros2-input's EuRoC sensor.yaml
// or Kalibr imu.yaml, already opened as `root`): gyroscope_noise_density, gyroscope_random_walk,
// accelerometer_noise_density, accelerometer_random_walk. Throws std::runtime_error with one line naming
// the file and the key: `FILE: KEY: missing (expected a positive number)` or `FILE: KEY: expected a
// positive number, got VALUE`.
ImuNoise read_imu_noise_model(const cv::FileNode& root, const std::filesystem::path& file);
// One positive finite number of such a file (rate_hz, update_rate, ...), with the same error lines.
double read_positive_number(const cv::FileNode& node, const std::filesystem::path& file, const char* key);

// Reads an IMU sensor.yaml alone (T_BS, rate_hz, the noise model): samples and source stay empty.
// Throws std::runtime_error with one line naming the file and the key.
ImuRecording read_imu_sensor_yaml(const std::filesystem::path& file);

// Reads imu0 of the dataset folder (or its mav0/). Throws std::runtime_error with one line naming the
// file, the line or field, and what was expected (a malformed row, stamps that do not increase, a
// missing noise figure, a non-finite value).
ImuRecording read_euroc_imu(const std::filesystem::path& dataset);

}  // namespace heslam
