// EuRoC ASL image lists and ground truth.
#include "tools/bench/frontend_offline/euroc_sequence.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <Eigen/Geometry>

namespace heslam::bench {
namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  std::string field;
  while (std::getline(stream, field, ',')) {
    while (!field.empty() && (field.back() == '\r' || field.back() == ' ')) field.pop_back();
    while (!field.empty() && field.front() == ' ') field.erase(field.begin());
    fields.push_back(field);
  }
  return fields;
}

// stamp -> image path of one camera's data.csv.
std::map<std::int64_t, std::filesystem::path> read_image_list(const std::filesystem::path& camera_dir) {
  const std::filesystem::path csv = camera_dir / "data.csv";
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(csv.string() + ": cannot open (expected an EuRoC camera data.csv)");
  std::map<std::int64_t, std::filesystem::path> images;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    const auto fields = split_csv(line);
    if (fields.size() < 2) {
      throw std::runtime_error(csv.string() + ":" + std::to_string(line_number) + ": expected 'timestamp,filename'");
    }
    try {
      images[std::stoll(fields[0])] = camera_dir / "data" / fields[1];
    } catch (const std::exception&) {
      throw std::runtime_error(csv.string() + ":" + std::to_string(line_number) + ": timestamp is not an integer");
    }
  }
  return images;
}

std::map<std::int64_t, Pose3> read_ground_truth(const std::filesystem::path& csv) {
  std::map<std::int64_t, Pose3> poses;
  std::ifstream in(csv);
  if (!in) return poses;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    const auto fields = split_csv(line);
    if (fields.size() < 8) {
      throw std::runtime_error(csv.string() + ":" + std::to_string(line_number) +
                               ": expected timestamp, p x y z, q w x y z");
    }
    try {
      Pose3 T = Pose3::Identity();
      T.translation() = Eigen::Vector3d(std::stod(fields[1]), std::stod(fields[2]), std::stod(fields[3]));
      T.linear() = Eigen::Quaterniond(std::stod(fields[4]), std::stod(fields[5]), std::stod(fields[6]),
                                      std::stod(fields[7]))
                       .normalized()
                       .toRotationMatrix();
      poses[std::stoll(fields[0])] = T;
    } catch (const std::invalid_argument&) {
      throw std::runtime_error(csv.string() + ":" + std::to_string(line_number) + ": non-numeric field");
    }
  }
  return poses;
}

}  // namespace

EurocSequence load_euroc_sequence(const std::filesystem::path& dataset_dir) {
  EurocSequence sequence;
  sequence.mav0_dir = std::filesystem::exists(dataset_dir / "mav0") ? dataset_dir / "mav0" : dataset_dir;
  const auto left = read_image_list(sequence.mav0_dir / "cam0");
  const auto right = read_image_list(sequence.mav0_dir / "cam1");
  for (const auto& [stamp, left_png] : left) {
    const auto it = right.find(stamp);
    if (it == right.end()) continue;
    sequence.frames.push_back({stamp, left_png, it->second});
  }
  sequence.T_WB_by_stamp = read_ground_truth(sequence.mav0_dir / "state_groundtruth_estimate0" / "data.csv");
  return sequence;
}

}  // namespace heslam::bench
