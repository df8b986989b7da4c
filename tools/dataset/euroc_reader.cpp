// EuRoC ASL layout: mav0/cam0|cam1/{data.csv, data/<stamp>.png, sensor.yaml}. Left and right rows are
// paired by stamp, so a camera that started earlier or dropped a frame costs only the unpaired rows.
#include <charconv>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tools/dataset/dataset_readers.hpp"

namespace heslam::dataset_detail {

namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

std::string unpaired_message(const fs::path& camera_dir, const CsvRow& row, const char* other) {
  return (camera_dir / "data.csv").string() + " line " + std::to_string(row.line) + ": stamp " +
         std::to_string(row.stamp_ns) + " has no " + other + " frame within the stereo tolerance";
}

}  // namespace

std::vector<CsvRow> read_camera_csv(const fs::path& camera_dir, StampOrder order) {
  const fs::path csv = camera_dir / "data.csv";
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv.string() + ": cannot be opened (expected the EuRoC frame list)");
  std::vector<CsvRow> rows;
  std::string text;
  int line = 0;
  while (std::getline(in, text)) {
    ++line;
    text = trim(text);
    if (text.empty() || text.front() == '#') continue;
    const auto comma = text.find(',');
    const std::string stamp_text = trim(text.substr(0, comma));
    CsvRow row;
    row.line = line;
    const auto [end, error] = std::from_chars(stamp_text.data(), stamp_text.data() + stamp_text.size(), row.stamp_ns);
    if (comma == std::string::npos || error != std::errc{} || end != stamp_text.data() + stamp_text.size() ||
        trim(text.substr(comma + 1)).empty()) {
      throw std::runtime_error(csv.string() + " line " + std::to_string(line) +
                               ": expected '<timestamp ns>,<file name>', got '" + text + "'");
    }
    if (order == StampOrder::kIncreasing && !rows.empty() && row.stamp_ns <= rows.back().stamp_ns) {
      throw std::runtime_error(csv.string() + " line " + std::to_string(line) + ": stamp " +
                               std::to_string(row.stamp_ns) + " is not after the previous stamp " +
                               std::to_string(rows.back().stamp_ns) + " (stamps must increase)");
    }
    row.image = camera_dir / "data" / trim(text.substr(comma + 1));
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw std::runtime_error(csv.string() + ": no frames listed (empty recording)");
  return rows;
}

fs::path find_euroc_mav0(const fs::path& path) {
  if (fs::exists(path / "mav0" / "cam0" / "data.csv")) return path / "mav0";
  if (fs::exists(path / "cam0" / "data.csv")) return path;
  return {};
}

StereoDataset read_euroc(const fs::path& mav0_dir, const DatasetOptions& options) {
  const fs::path left_dir = mav0_dir / "cam0";
  const fs::path right_dir = mav0_dir / "cam1";
  const std::vector<CsvRow> left = read_camera_csv(left_dir, StampOrder::kIncreasing);
  const std::vector<CsvRow> right = read_camera_csv(right_dir, StampOrder::kIncreasing);

  StereoDataset dataset;
  if (options.load_calibration) dataset.calibration = load_euroc_calibration(mav0_dir);

  // Merge walk over the two sorted lists; the earlier unpaired row is the one skipped.
  std::size_t l = 0;
  std::size_t r = 0;
  auto skip = [&](const std::string& message) {
    if (options.strict) throw std::runtime_error(message + " (--strict)");
    dataset.warnings.push_back(message);
    ++dataset.skipped_rows;
  };
  while (l < left.size() && r < right.size()) {
    const std::int64_t offset_ns = right[r].stamp_ns - left[l].stamp_ns;
    if (offset_ns > options.max_stereo_offset_ns) {
      skip(unpaired_message(left_dir, left[l++], "cam1"));
    } else if (-offset_ns > options.max_stereo_offset_ns) {
      skip(unpaired_message(right_dir, right[r++], "cam0"));
    } else {
      dataset.frames.push_back({left[l].stamp_ns, right[r].stamp_ns, left[l].image, right[r].image});
      ++l;
      ++r;
    }
  }
  for (; l < left.size(); ++l) skip(unpaired_message(left_dir, left[l], "cam1"));
  for (; r < right.size(); ++r) skip(unpaired_message(right_dir, right[r], "cam0"));
  if (dataset.frames.empty()) {
    throw std::runtime_error(mav0_dir.string() + ": no cam0 stamp matches a cam1 stamp (left/right stamp mismatch)");
  }
  return dataset;
}

}  // namespace heslam::dataset_detail
