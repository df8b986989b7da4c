// Writing a kidnapped-camera copy of an EuRoC folder.
#include "tools/bench/frontend_offline/kidnapped_copy.hpp"

#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tools/bench/frontend_offline/euroc_sequence.hpp"

namespace heslam::bench {
namespace {

namespace fs = std::filesystem;

// The frame period past the end of a one-frame source, which has none: EuRoC's 20 Hz.
constexpr std::int64_t kOneFrameSourcePeriod_ns = 50'000'000;

void link_or_copy(const fs::path& target, const fs::path& link) {
  std::error_code error;
  fs::create_symlink(fs::absolute(target), link, error);
  if (error) fs::copy_file(target, link, fs::copy_options::overwrite_existing);
}

// The plan's frames: frame k of the copy shows source frame shown[k] (-1: black) at stamps[k].
struct Schedule {
  std::vector<int> shown;
  std::vector<std::int64_t> stamps;
};

Schedule make_schedule(const EurocSequence& source, const fs::path& source_dataset, const KidnapPlan& plan) {
  const int source_frames = static_cast<int>(source.frames.size());
  const int frames = plan.replay_frames < 0 ? source_frames : plan.replay_first + plan.replay_frames;
  const int replayed = frames - plan.replay_first;
  if (plan.black_first < 0 || plan.black_first > plan.replay_first || plan.replay_first > source_frames ||
      plan.replay_source < 0 || replayed < 0 ||
      (plan.replay_frames >= 0 && plan.replay_source + replayed > source_frames)) {
    throw std::runtime_error(source_dataset.string() + ": kidnap plan (black from " + std::to_string(plan.black_first) +
                             ", replay from " + std::to_string(plan.replay_first) + " of source frames " +
                             std::to_string(plan.replay_source) + " on) does not fit its " +
                             std::to_string(source_frames) + " frames");
  }
  const std::int64_t first_stamp = source.frames.front().stamp_ns;
  const std::int64_t last_stamp = source.frames.back().stamp_ns;
  const std::int64_t period_ns =
      source_frames > 1 ? (last_stamp - first_stamp) / (source_frames - 1) : kOneFrameSourcePeriod_ns;
  Schedule result;
  for (int k = 0; k < frames; ++k) {
    int shown = k;
    if (k >= plan.black_first && k < plan.replay_first) shown = -1;
    if (k >= plan.replay_first) shown = plan.replay_source + k - plan.replay_first;
    if (shown >= source_frames) break;  // replaying up to the end of the source
    result.shown.push_back(shown);
    result.stamps.push_back(k < source_frames ? source.frames[static_cast<std::size_t>(k)].stamp_ns
                                              : last_stamp + (k - source_frames + 1) * period_ns);
  }
  return result;
}

// The source's ground-truth rows (the text after the stamp) by stamp; empty without ground truth.
std::map<std::int64_t, std::string> ground_truth_rows(const fs::path& csv, std::string& header) {
  std::map<std::int64_t, std::string> rows;
  std::ifstream in(csv);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      header = line;
      continue;
    }
    const std::size_t comma = line.find(',');
    try {
      if (comma == std::string::npos) throw std::invalid_argument("no comma");
      rows[std::stoll(line.substr(0, comma))] = line.substr(comma);
    } catch (const std::logic_error&) {
      throw std::runtime_error(csv.string() + ": expected 'timestamp,...' rows, got '" + line + "'");
    }
  }
  return rows;
}

void write_ground_truth(const EurocSequence& source, const Schedule& copy, const fs::path& mav0) {
  const fs::path source_csv = source.mav0_dir / "state_groundtruth_estimate0" / "data.csv";
  std::string header;
  const auto rows = ground_truth_rows(source_csv, header);
  if (rows.empty()) return;
  const fs::path csv_path = mav0 / "state_groundtruth_estimate0" / "data.csv";
  fs::create_directories(csv_path.parent_path());
  std::ofstream csv(csv_path);
  if (!csv) throw std::runtime_error(csv_path.string() + ": cannot write");
  if (!header.empty()) csv << header << '\n';
  for (std::size_t k = 0; k < copy.shown.size(); ++k) {
    if (copy.shown[k] < 0) continue;
    const auto row = rows.find(source.frames[static_cast<std::size_t>(copy.shown[k])].stamp_ns);
    if (row != rows.end()) csv << copy.stamps[k] << row->second << '\n';
  }
}

}  // namespace

int write_kidnapped_copy(const fs::path& source_dataset, const fs::path& dest_dataset, const KidnapPlan& plan) {
  const EurocSequence source = load_euroc_sequence(source_dataset);
  if (source.frames.empty()) throw std::runtime_error(source_dataset.string() + ": no stereo frames");
  const Schedule copy = make_schedule(source, source_dataset, plan);
  const fs::path mav0 = dest_dataset / "mav0";
  const cv::Mat first = cv::imread(source.frames.front().left_png.string(), cv::IMREAD_GRAYSCALE);
  if (first.empty()) throw std::runtime_error(source.frames.front().left_png.string() + ": cannot read image");
  const cv::Mat black = cv::Mat::zeros(first.size(), CV_8UC1);

  for (const char* camera : {"cam0", "cam1"}) {
    const fs::path dir = mav0 / camera;
    fs::create_directories(dir / "data");
    link_or_copy(source.mav0_dir / camera / "sensor.yaml", dir / "sensor.yaml");
    const fs::path black_png = dir / "data" / "black.png";
    if (!cv::imwrite(black_png.string(), black)) throw std::runtime_error(black_png.string() + ": cannot write");
    std::ofstream csv(dir / "data.csv");
    if (!csv) throw std::runtime_error((dir / "data.csv").string() + ": cannot write");
    csv << "#timestamp [ns],filename\n";
    for (std::size_t k = 0; k < copy.shown.size(); ++k) {
      const std::int64_t stamp = copy.stamps[k];
      if (copy.shown[k] < 0) {
        csv << stamp << ",black.png\n";
        continue;
      }
      const EurocFrame& image = source.frames[static_cast<std::size_t>(copy.shown[k])];
      const fs::path png = std::string(camera) == "cam0" ? image.left_png : image.right_png;
      const std::string name = std::to_string(stamp) + ".png";
      link_or_copy(png, dir / "data" / name);
      csv << stamp << ',' << name << '\n';
    }
  }
  write_ground_truth(source, copy, mav0);
  if (fs::exists(source.mav0_dir / "body.yaml")) link_or_copy(source.mav0_dir / "body.yaml", mav0 / "body.yaml");
  return static_cast<int>(load_euroc_sequence(dest_dataset).frames.size());
}

}  // namespace heslam::bench
