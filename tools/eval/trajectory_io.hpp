// Reading and writing trajectories in the formats of the field. heslam itself writes TUM.
//
// API:
//   Trajectory t = read_trajectory("KITTI_00_ORB.txt", Format::kitti);
//   Trajectory t = read_trajectory(path, ReadOptions{.times_path = "times.txt"});  // format detected
//   write_trajectory("out.txt", t, Format::tum);
//   Format f = detect_format(path);           // .csv -> EuRoC; else 8 columns -> TUM, 12/13 -> KITTI
//   Pose3 T_BS = read_euroc_extrinsic("mav0/cam0/sensor.yaml");
// Formats:
//   tum    "stamp_s x y z qx qy qz qw" (heslam's own output format)
//   kitti  12 numbers per line (row-major 3x4 T_wc), optionally preceded by the frame index;
//          stamps come from a times file (one stamp per line, indexed by frame index)
//   euroc  ground-truth csv: "stamp_ns, x y z, qw qx qy qz" (8 columns) or the 17-column
//          state_groundtruth_estimate0 layout (velocity and biases ignored); poses of the body frame
// Every reader throws std::runtime_error naming file:line for malformed rows, and the file for an
// empty trajectory.
#pragma once

#include <filesystem>
#include <optional>
#include <string_view>

#include "components/core/geometry/pose.hpp"
#include "tools/eval/trajectory.hpp"

namespace heslam::eval {

enum class Format {
  tum,
  kitti,
  euroc,
  // What heslam writes (the recorder, the frontend's tests): TUM, stamps in seconds.
  heslam_default = tum,
};

// "tum", "heslam" (an alias of tum), "kitti", "euroc"; nullopt otherwise.
std::optional<Format> parse_format(std::string_view name);
const char* format_name(Format format);
// Looks at the extension and the first data row; throws when neither tells.
Format detect_format(const std::filesystem::path& path);

struct ReadOptions {
  // Detected from the file when unset.
  std::optional<Format> format{};
  // KITTI only: a times.txt giving the stamp of each frame index. Empty: no stamps.
  std::filesystem::path times_path{};
  // An EuRoC sensor.yaml whose T_BS turns body poses into sensor (camera) poses: T_wc = T_wb * T_bs.
  // Empty: poses are kept as read.
  std::filesystem::path extrinsic_path{};
};

Trajectory read_trajectory(const std::filesystem::path& path, const ReadOptions& options = {});
void write_trajectory(const std::filesystem::path& path, const Trajectory& trajectory, Format format = Format::tum);

// The T_BS matrix (sensor to body) of an EuRoC sensor.yaml.
Pose3 read_euroc_extrinsic(const std::filesystem::path& sensor_yaml);

// Per-format entry points, used by read_trajectory / write_trajectory.
Trajectory read_tum(const std::filesystem::path& path);
Trajectory read_kitti(const std::filesystem::path& path);
Trajectory read_euroc(const std::filesystem::path& path);
void write_tum(const std::filesystem::path& path, const Trajectory& trajectory);
void write_kitti(const std::filesystem::path& path, const Trajectory& trajectory);
void write_euroc(const std::filesystem::path& path, const Trajectory& trajectory);

}  // namespace heslam::eval
