// The per-format readers behind open_dataset(); one file each (euroc_reader.cpp, kitti_reader.cpp).
#pragma once

#include <filesystem>

#include "tools/dataset/stereo_dataset.hpp"

namespace heslam::dataset_detail {

// `mav0_dir` holds cam0/ and cam1/ (each data.csv, data/, sensor.yaml).
StereoDataset read_euroc(const std::filesystem::path& mav0_dir, const DatasetOptions& options);
// `sequence_dir` holds times.txt, calib.txt, image_0/, image_1/.
StereoDataset read_kitti(const std::filesystem::path& sequence_dir, const DatasetOptions& options);

// The EuRoC folder (holding cam0/) for a path naming either the sequence or its mav0/, or empty.
std::filesystem::path find_euroc_mav0(const std::filesystem::path& path);
bool looks_like_kitti(const std::filesystem::path& path);

}  // namespace heslam::dataset_detail
