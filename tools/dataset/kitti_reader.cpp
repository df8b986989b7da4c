// KITTI odometry layout: times.txt (seconds, one per frame), calib.txt (P0, P1), image_0/ and image_1/
// with <index:06>.png. Images are already rectified; the size comes from the first left image because
// calib.txt does not state it.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <opencv2/core.hpp>

#include "tools/dataset/dataset_readers.hpp"
#include "tools/dataset/stereo_images.hpp"

namespace heslam::dataset_detail {

namespace fs = std::filesystem;

namespace {

constexpr double kNsPerS = 1e9;
constexpr int kIndexDigits = 6;  // KITTI names images 000000.png, 000001.png, ...

fs::path image_path(const fs::path& folder, std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%0*zu.png", kIndexDigits, index);
  return folder / name;
}

}  // namespace

bool looks_like_kitti(const fs::path& path) {
  return fs::exists(path / "times.txt") && fs::is_directory(path / "image_0");
}

StereoDataset read_kitti(const fs::path& sequence_dir, const DatasetOptions& options) {
  const fs::path times_txt = sequence_dir / "times.txt";
  std::ifstream in(times_txt);
  if (!in) throw std::runtime_error(times_txt.string() + ": cannot be opened (expected the KITTI frame times)");

  StereoDataset dataset;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream fields(text);
    double stamp_s = 0.0;
    std::string rest;
    if (!(fields >> stamp_s) || (fields >> rest) || !std::isfinite(stamp_s) || stamp_s < 0.0) {
      throw std::runtime_error(times_txt.string() + " line " + std::to_string(line) +
                               ": expected one time in seconds, got '" + text + "'");
    }
    const auto stamp_ns = static_cast<std::int64_t>(std::llround(stamp_s * kNsPerS));
    if (!dataset.frames.empty() && stamp_ns <= dataset.frames.back().stamp_ns) {
      throw std::runtime_error(times_txt.string() + " line " + std::to_string(line) + ": time " + text +
                               " s is not after the previous time (times must increase)");
    }
    const std::size_t index = dataset.frames.size();
    dataset.frames.push_back(
        {stamp_ns, stamp_ns, image_path(sequence_dir / "image_0", index), image_path(sequence_dir / "image_1", index)});
  }
  if (dataset.frames.empty()) throw std::runtime_error(times_txt.string() + ": no frames listed (empty recording)");
  if (!options.load_calibration) return dataset;

  // The first decodable left image gives the size calib.txt leaves out.
  cv::Mat first;
  for (const StereoFrameFiles& frame : dataset.frames) {
    try {
      first = load_image_file(frame.left);
      break;
    } catch (const std::runtime_error&) {
      // missing or damaged: the replay reports it when the frame is due; try the next one
    }
  }
  if (first.empty()) {
    throw std::runtime_error((sequence_dir / "image_0").string() + ": no readable image (empty recording)");
  }
  dataset.calibration = load_kitti_calibration(sequence_dir / "calib.txt", first.cols, first.rows);
  return dataset;
}

}  // namespace heslam::dataset_detail
