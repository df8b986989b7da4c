// Format detection, dispatch to the per-format readers, and time-window selection.
#include "tools/dataset/stereo_dataset.hpp"

#include <cstdio>
#include <stdexcept>

#include "tools/dataset/dataset_readers.hpp"

namespace heslam {

namespace fs = std::filesystem;

namespace {
constexpr double kNsPerS = 1e9;
}  // namespace

DatasetFormat parse_dataset_format(const std::string& name) {
  if (name == "auto") return DatasetFormat::kAuto;
  if (name == "euroc") return DatasetFormat::kEuroc;
  if (name == "kitti") return DatasetFormat::kKitti;
  throw std::runtime_error("--format: unknown format '" + name + "' (expected euroc, kitti or auto)");
}

const char* to_string(DatasetFormat format) {
  switch (format) {
    case DatasetFormat::kEuroc: return "euroc";
    case DatasetFormat::kKitti: return "kitti";
    case DatasetFormat::kAuto: break;
  }
  return "auto";
}

double StereoDataset::duration_s() const {
  if (frames.size() < 2) return 0.0;
  return static_cast<double>(frames.back().stamp_ns - frames.front().stamp_ns) / kNsPerS;
}

DatasetFormat detect_dataset_format(const fs::path& path) {
  if (!fs::is_directory(path)) {
    throw std::runtime_error(path.string() + ": not a folder (expected an EuRoC or KITTI sequence)");
  }
  if (!dataset_detail::find_euroc_mav0(path).empty()) return DatasetFormat::kEuroc;
  if (dataset_detail::looks_like_kitti(path)) return DatasetFormat::kKitti;
  throw std::runtime_error(path.string() +
                           ": no EuRoC (mav0/cam0/data.csv) or KITTI (times.txt + image_0/) layout found");
}

StereoDataset open_dataset(const fs::path& path, const DatasetOptions& options) {
  DatasetFormat format = options.format;
  if (format == DatasetFormat::kAuto) format = detect_dataset_format(path);
  if (!fs::is_directory(path)) throw std::runtime_error(path.string() + ": not a folder");
  StereoDataset dataset;
  DatasetOptions own = options;
  if (!options.calibration_file.empty()) own.load_calibration = false;
  if (format == DatasetFormat::kEuroc) {
    fs::path mav0 = dataset_detail::find_euroc_mav0(path);
    if (mav0.empty()) {
      throw std::runtime_error(path.string() + ": not an EuRoC folder (expected mav0/cam0/data.csv)");
    }
    dataset = dataset_detail::read_euroc(mav0, own);
  } else {
    if (!dataset_detail::looks_like_kitti(path)) {
      throw std::runtime_error(path.string() + ": not a KITTI sequence (expected times.txt and image_0/)");
    }
    dataset = dataset_detail::read_kitti(path, own);
  }
  if (!options.calibration_file.empty() && options.load_calibration) {
    dataset.calibration = load_orbslam_settings(options.calibration_file);
  }
  dataset.format = format;
  dataset.root = path;
  return dataset;
}

void select_time_window(StereoDataset& dataset, double offset_s, double duration_s) {
  if (offset_s < 0.0) throw std::runtime_error("--start-offset: must be >= 0 seconds");
  if (dataset.frames.empty()) return;
  const std::int64_t first_ns = dataset.frames.front().stamp_ns;
  const auto begin_ns = static_cast<std::int64_t>(offset_s * kNsPerS);
  const bool to_end = duration_s <= 0.0;
  const auto end_ns = begin_ns + static_cast<std::int64_t>(duration_s * kNsPerS);
  std::vector<StereoFrameFiles> kept;
  for (const StereoFrameFiles& frame : dataset.frames) {
    const std::int64_t since_first_ns = frame.stamp_ns - first_ns;
    if (since_first_ns >= begin_ns && (to_end || since_first_ns < end_ns)) kept.push_back(frame);
  }
  if (kept.empty()) {
    char window[160];
    if (to_end) {
      std::snprintf(window, sizeof(window), "[%g s, end) of a %.3g s recording", offset_s, dataset.duration_s());
    } else {
      std::snprintf(window, sizeof(window), "[%g s, %g s) of a %.3g s recording", offset_s, offset_s + duration_s,
                    dataset.duration_s());
    }
    throw std::runtime_error(std::string("--start-offset/--duration: no frame in ") + window);
  }
  dataset.frames = std::move(kept);
}

}  // namespace heslam
