// Format choice and the parts shared by every reader: times files, the EuRoC extrinsic, checks.
#include "tools/eval/trajectory_io.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "tools/eval/line_reader.hpp"

namespace heslam::eval {

namespace {

constexpr std::size_t kTumColumns = 8;
constexpr std::size_t kKittiColumns = 12;
constexpr std::size_t kIndexedKittiColumns = 13;
constexpr std::size_t kEurocStateColumns = 17;

std::vector<double> read_times(const std::filesystem::path& path) {
  LineReader reader(path);
  std::vector<double> stamps_s;
  while (reader.next()) {
    reader.expect_columns(1, 0, "times file: one stamp in seconds per line");
    stamps_s.push_back(reader.values()[0]);
  }
  return stamps_s;
}

void attach_times(Trajectory& trajectory, const std::filesystem::path& times_path) {
  const std::vector<double> stamps_s = read_times(times_path);
  trajectory.stamps_s.clear();
  for (const std::int64_t frame_id : trajectory.frame_ids) {
    if (frame_id < 0 || static_cast<std::size_t>(frame_id) >= stamps_s.size()) {
      throw std::runtime_error(times_path.string() + ": has " + std::to_string(stamps_s.size()) + " stamps, but " +
                               trajectory.name + " has frame index " + std::to_string(frame_id));
    }
    trajectory.stamps_s.push_back(stamps_s[static_cast<std::size_t>(frame_id)]);
  }
}

void check_stamps_increase(const Trajectory& trajectory) {
  for (std::size_t i = 1; i < trajectory.stamps_s.size(); ++i) {
    if (!(trajectory.stamps_s[i] >= trajectory.stamps_s[i - 1])) {
      throw std::runtime_error(trajectory.name + ": time stamps go backwards at pose " + std::to_string(i + 1) + " (" +
                               std::to_string(trajectory.stamps_s[i]) + " s after " +
                               std::to_string(trajectory.stamps_s[i - 1]) + " s)");
    }
  }
}

}  // namespace

std::optional<Format> parse_format(std::string_view name) {
  if (name == "tum" || name == "heslam") return Format::tum;
  if (name == "kitti") return Format::kitti;
  if (name == "euroc") return Format::euroc;
  return std::nullopt;
}

const char* format_name(Format format) {
  switch (format) {
    case Format::tum: return "tum";
    case Format::kitti: return "kitti";
    case Format::euroc: return "euroc";
  }
  return "?";
}

Format detect_format(const std::filesystem::path& path) {
  if (path.extension() == ".csv") return Format::euroc;
  LineReader reader(path);
  if (!reader.next()) throw std::runtime_error(path.string() + ": no poses (empty file)");
  const std::size_t columns = reader.values().size();
  if (columns == kTumColumns) return Format::tum;
  if (columns == kKittiColumns || columns == kIndexedKittiColumns) return Format::kitti;
  if (columns == kEurocStateColumns) return Format::euroc;
  reader.fail("cannot tell the format from " + std::to_string(columns) +
              " columns (TUM has 8, KITTI 12 or 13, EuRoC 8 or 17 in a .csv); pass --gt-format / "
              "--est-format");
}

Trajectory read_trajectory(const std::filesystem::path& path, const ReadOptions& options) {
  const Format format = options.format ? *options.format : detect_format(path);
  Trajectory trajectory;
  switch (format) {
    case Format::tum: trajectory = read_tum(path); break;
    case Format::kitti: trajectory = read_kitti(path); break;
    case Format::euroc: trajectory = read_euroc(path); break;
  }
  if (trajectory.empty()) throw std::runtime_error(path.string() + ": no poses (empty file)");
  if (!options.times_path.empty()) {
    if (format != Format::kitti) {
      throw std::runtime_error(path.string() + ": a times file only applies to KITTI pose files, this is " +
                               format_name(format));
    }
    attach_times(trajectory, options.times_path);
  }
  check_stamps_increase(trajectory);
  if (!options.extrinsic_path.empty()) {
    const Pose3 T_bs = read_euroc_extrinsic(options.extrinsic_path);
    for (Pose3& T_wb : trajectory.poses_wc) T_wb = T_wb * T_bs;
    if (trajectory.frame == PoseFrame::body) trajectory.frame = PoseFrame::cam0;
  }
  return trajectory;
}

void write_trajectory(const std::filesystem::path& path, const Trajectory& trajectory, Format format) {
  switch (format) {
    case Format::tum: write_tum(path, trajectory); return;
    case Format::kitti: write_kitti(path, trajectory); return;
    case Format::euroc: write_euroc(path, trajectory); return;
  }
}

Pose3 read_euroc_extrinsic(const std::filesystem::path& sensor_yaml) {
  std::ifstream in(sensor_yaml);
  if (!in) throw std::runtime_error("cannot open " + sensor_yaml.string());
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  // EuRoC files lack the "%YAML" directive cv::FileStorage wants.
  if (yaml.rfind("%YAML", 0) != 0) yaml = "%YAML:1.0\n" + yaml;
  const std::string where = sensor_yaml.string() + ": T_BS";
  std::vector<double> data;
  try {
    cv::FileStorage storage(yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY);
    const cv::FileNode node = storage["T_BS"];
    if (node.empty()) throw std::runtime_error(sensor_yaml.string() + ": no field T_BS");
    node["data"] >> data;
  } catch (const cv::Exception& e) {
    throw std::runtime_error(sensor_yaml.string() + ": not readable as YAML (" + e.err + ")");
  }
  if (data.size() != 16) {
    throw std::runtime_error(where + ".data: expected 16 numbers (row-major 4x4), got " + std::to_string(data.size()));
  }
  Pose3 T_bs = Pose3::Identity();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) T_bs.matrix()(row, col) = data[static_cast<std::size_t>(4 * row + col)];
  }
  return T_bs;
}

}  // namespace heslam::eval
