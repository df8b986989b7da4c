// A photometrically transformed copy of a stereo dataset folder (EuRoC ASL or KITTI odometry): the
// same layout, calibration, ground truth and every other file byte for byte, with each stereo pair's
// two images passed through apply_to_pair(). What heslam-photometric writes, so the full system (replay
// -> frontend -> mapper -> loop closer) can be run on the images heslam-frontend-offline's --variant /
// --stereo-gain options give the tracker alone.
#pragma once

#include <cstddef>
#include <filesystem>
#include <vector>

#include "tools/dataset/stereo_dataset.hpp"
#include "tools/photometric/photometric_variant.hpp"

namespace heslam::photometric {

struct DatasetCopyOptions {
  DatasetFormat format = DatasetFormat::kAuto;
  PhotometricVariant variant = PhotometricVariant::kNone;
  // Empty: equal exposure; several entries split the sequence into equal consecutive blocks of frames
  // (stereo_gain_at), as heslam-frontend-offline does over a whole run.
  std::vector<StereoGain> stereo_gain;
};

struct DatasetCopySummary {
  DatasetFormat format = DatasetFormat::kAuto;
  std::size_t frames = 0;        // stereo pairs transformed (two images each)
  std::size_t copied_files = 0;  // every other file, unchanged
  // Share of pixels at grey 255 after the transform, over all pairs: how much each camera is clipped.
  double left_saturated_share = 0.0;
  double right_saturated_share = 0.0;
};

// Writes the copy of `input` to `output`, which must not exist yet or be an empty folder, and must not
// lie inside `input`. Throws std::runtime_error with one line naming the file at fault (unreadable or
// unwritable image, not a dataset, output not empty); on any error after `output` was created it is
// removed again, so a failed copy never looks like a finished one.
DatasetCopySummary write_dataset_copy(const std::filesystem::path& input, const std::filesystem::path& output,
                                      const DatasetCopyOptions& options);

}  // namespace heslam::photometric
