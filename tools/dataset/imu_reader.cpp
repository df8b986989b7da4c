// EuRoC imu0 reader (imu_reader.hpp).
#include "tools/dataset/imu_reader.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "runtime/quote_value.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

fs::path imu_dir(const fs::path& dataset) {
  if (fs::exists(dataset / "mav0" / "imu0" / "data.csv")) return dataset / "mav0" / "imu0";
  return dataset / "imu0";
}

[[noreturn]] void fail(const fs::path& file, const std::string& where, const std::string& what) {
  throw std::runtime_error(file.string() + ": " + where + ": " + what);
}

void read_sensor_yaml(const fs::path& file, ImuRecording& recording) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open (expected the IMU's sensor.yaml)");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  if (yaml.rfind("%YAML", 0) != 0) yaml = "%YAML:1.0\n" + yaml;
  cv::FileStorage fs;
  try {
    fs.open(yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
  } catch (const cv::Exception& error) {
    throw std::runtime_error(file.string() + ": not valid YAML (" + error.err + ")");
  }
  recording.rate_hz = read_positive_number(fs["rate_hz"], file, "rate_hz");
  recording.noise = read_imu_noise_model(fs.root(), file);
  const cv::FileNode data = fs["T_BS"]["data"];
  if (!data.isSeq() || data.size() != 16) fail(file, "T_BS", "expected {rows: 4, cols: 4, data: [16 numbers]}");
  Eigen::Matrix4d T;
  for (int i = 0; i < 16; ++i) {
    const cv::FileNode item = data[i];
    if (!item.isReal() && !item.isInt()) fail(file, "T_BS.data", "expected 16 numbers");
    T(i / 4, i % 4) = static_cast<double>(item);
  }
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  if (!T.allFinite() || (R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3 || R.determinant() < 0.0) {
    fail(file, "T_BS", "expected a rigid transform (a rotation and a translation)");
  }
  recording.T_BS.matrix() = T;
  recording.T_BS.makeAffine();
}

}  // namespace

double read_positive_number(const cv::FileNode& node, const fs::path& file, const char* key) {
  if (node.empty() || (!node.isReal() && !node.isInt())) fail(file, key, "missing (expected a positive number)");
  const double value = static_cast<double>(node);
  if (!std::isfinite(value) || !(value > 0.0)) {
    fail(file, key, "expected a positive number, got " + std::to_string(value));
  }
  return value;
}

ImuNoise read_imu_noise_model(const cv::FileNode& root, const fs::path& file) {
  ImuNoise noise;
  noise.gyro_noise_density = read_positive_number(root["gyroscope_noise_density"], file, "gyroscope_noise_density");
  noise.gyro_random_walk = read_positive_number(root["gyroscope_random_walk"], file, "gyroscope_random_walk");
  noise.accel_noise_density =
      read_positive_number(root["accelerometer_noise_density"], file, "accelerometer_noise_density");
  noise.accel_random_walk = read_positive_number(root["accelerometer_random_walk"], file, "accelerometer_random_walk");
  return noise;
}

ImuRecording read_imu_sensor_yaml(const fs::path& file) {
  ImuRecording recording;
  read_sensor_yaml(file, recording);
  return recording;
}

bool has_euroc_imu(const fs::path& dataset) { return fs::exists(imu_dir(dataset) / "data.csv"); }

ImuRecording read_euroc_imu(const fs::path& dataset) {
  const fs::path dir = imu_dir(dataset);
  ImuRecording recording;
  recording.source = dir / "data.csv";
  read_sensor_yaml(dir / "sensor.yaml", recording);
  std::ifstream in(recording.source);
  if (!in) throw std::runtime_error(recording.source.string() + ": cannot open (expected the EuRoC IMU readings)");
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.empty() || text.front() == '#') continue;
    const std::string where = "line " + std::to_string(line);
    const auto bad_row = [&] {
      fail(recording.source, where,
           "expected '<timestamp ns>,wx,wy,wz,ax,ay,az' (7 numbers), got '" + runtime::quote_value(text) + "'");
    };
    std::vector<std::string> fields;
    std::stringstream row(text);
    std::string field;
    while (std::getline(row, field, ',')) fields.push_back(field);
    if (fields.size() != 7) bad_row();
    ImuSample sample;
    const auto trim = [](const std::string& s) {
      const auto first = s.find_first_not_of(" \t");
      const auto last = s.find_last_not_of(" \t");
      return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
    };
    const std::string stamp = trim(fields[0]);
    const auto [end, error] = std::from_chars(stamp.data(), stamp.data() + stamp.size(), sample.stamp_ns);
    if (error != std::errc{} || end != stamp.data() + stamp.size()) bad_row();
    double values[6];
    for (int i = 0; i < 6; ++i) {
      const std::string number = trim(fields[i + 1]);
      const auto [number_end, number_error] = std::from_chars(number.data(), number.data() + number.size(), values[i]);
      if (number_error != std::errc{} || number_end != number.data() + number.size()) bad_row();
      if (!std::isfinite(values[i])) fail(recording.source, where, "expected finite readings, got '" + number + "'");
    }
    sample.gyro_rad_s = Eigen::Vector3d(values[0], values[1], values[2]);
    sample.accel_m_s2 = Eigen::Vector3d(values[3], values[4], values[5]);
    if (!recording.samples.empty() && sample.stamp_ns <= recording.samples.back().stamp_ns) {
      fail(recording.source, where,
           "stamp " + std::to_string(sample.stamp_ns) + " is not after the previous one (stamps must increase)");
    }
    recording.samples.push_back(sample);
  }
  if (recording.samples.empty()) fail(recording.source, "readings", "none (an empty IMU recording)");
  return recording;
}

}  // namespace heslam
