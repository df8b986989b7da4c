// The per-format readers behind open_dataset(); one file each (euroc_reader.cpp, kitti_reader.cpp). The
// EuRoC frame list and folder finder are also heslam-camera's (tools/camera/stereo_capture.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "tools/dataset/stereo_dataset.hpp"

namespace heslam::dataset_detail {

// `mav0_dir` holds cam0/ and cam1/ (each data.csv, data/, sensor.yaml).
StereoDataset read_euroc(const std::filesystem::path& mav0_dir, const DatasetOptions& options);
// `sequence_dir` holds times.txt, calib.txt, image_0/, image_1/.
StereoDataset read_kitti(const std::filesystem::path& sequence_dir, const DatasetOptions& options);

// One row of an EuRoC camera's data.csv ("<timestamp ns>,<file name>"): the image is data/<file name>.
struct CsvRow {
  std::int64_t stamp_ns = 0;
  std::filesystem::path image;
  int line = 0;  // 1-based, for messages
};
// kIncreasing: a stamp not after the previous one throws (a recording); kAsListed: rows in file order,
// whatever their stamps (heslam-camera plays them as a driver delivered them and counts the backwards ones).
enum class StampOrder { kIncreasing, kAsListed };
// `camera_dir`/data.csv; throws one line naming the file and line for a malformed row or no rows.
std::vector<CsvRow> read_camera_csv(const std::filesystem::path& camera_dir, StampOrder order);

// The EuRoC folder (holding cam0/) for a path naming either the sequence or its mav0/, or empty.
std::filesystem::path find_euroc_mav0(const std::filesystem::path& path);
bool looks_like_kitti(const std::filesystem::path& path);

}  // namespace heslam::dataset_detail
