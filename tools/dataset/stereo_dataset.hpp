// A stereo recording on disk (EuRoC ASL folder or KITTI odometry sequence) as a list of frame files
// plus the rig's raw calibration. DDS-free: the replay publishes it; the offline benchmarks,
// heslam-vocab, the photometric copies and tests read it directly.
//
//   StereoDataset dataset = open_dataset("/data/V1_01_easy", {});   // format auto-detected
//   for (const StereoFrameFiles& frame : dataset.frames) {
//     StereoImages images = load_stereo_images(frame);            // throws on a missing/corrupt file
//   }
//
// Opening throws std::runtime_error whose what() is one line naming the file (and line) at fault.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "components/core/camera/stereo_calibration.hpp"

namespace heslam {

enum class DatasetFormat { kAuto, kEuroc, kKitti };

// "euroc", "kitti", "auto"; throws on anything else.
DatasetFormat parse_dataset_format(const std::string& name);
const char* to_string(DatasetFormat format);

struct DatasetOptions {
  DatasetFormat format = DatasetFormat::kAuto;
  // EuRoC: a left and a right row form a pair when their stamps differ by at most this. The EuRoC
  // cameras are hardware-triggered and share stamps exactly; 1 ms tolerates re-stamped recordings
  // while staying far below a 20 Hz frame period.
  std::int64_t max_stereo_offset_ns = 1'000'000;
  // true: a row without a partner in the other camera is an error instead of a skipped, counted row.
  bool strict = false;
  // false: the frame lists only, the calibration left empty (for callers that load their own).
  bool load_calibration = true;
  // Not empty: the calibration is this ORB-SLAM2 / ORB-SLAM3 stereo settings file's instead of the
  // dataset's own (sensor.yaml / calib.txt), e.g. a user's recalibration of the rig.
  std::filesystem::path calibration_file{};
};

// One stereo pair: where its two images are and when it was taken (the left camera's stamp).
struct StereoFrameFiles {
  std::int64_t stamp_ns = 0;
  std::int64_t right_stamp_ns = 0;  // the right row's own stamp (equal for synchronised rigs)
  std::filesystem::path left;
  std::filesystem::path right;
};

struct StereoDataset {
  DatasetFormat format = DatasetFormat::kAuto;
  std::filesystem::path root;            // the folder holding mav0/ (EuRoC) or times.txt (KITTI)
  StereoCalibration calibration;         // raw cameras, as the calibration loaders return them
  std::vector<StereoFrameFiles> frames;  // strictly increasing stamp_ns
  std::vector<std::string> warnings;     // one line per skipped row (unpaired left or right)
  int skipped_rows = 0;

  // Seconds from the first to the last frame (0 for fewer than two frames).
  double duration_s() const;
};

// Which layout `path` holds; throws "PATH: no EuRoC ... or KITTI ... layout found" if neither.
DatasetFormat detect_dataset_format(const std::filesystem::path& path);

// Reads the frame lists and the calibration. Throws on an empty folder, unreadable calibration,
// non-increasing stamps, malformed rows, and (strict) unpaired rows.
StereoDataset open_dataset(const std::filesystem::path& path, const DatasetOptions& options = {});

// Keeps the frames with offset_s <= stamp - first stamp < offset_s + duration_s (duration_s <= 0:
// to the end). Throws when the window is empty so a typo does not look like an empty recording.
void select_time_window(StereoDataset& dataset, double offset_s, double duration_s);

}  // namespace heslam
