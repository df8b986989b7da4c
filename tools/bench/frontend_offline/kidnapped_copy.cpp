// Writing a kidnapped-camera copy of an EuRoC folder.
#include "tools/bench/frontend_offline/kidnapped_copy.hpp"

#include <fstream>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tools/bench/frontend_offline/euroc_sequence.hpp"

namespace heslam::bench {
namespace {

namespace fs = std::filesystem;

void link_or_copy(const fs::path& target, const fs::path& link) {
  std::error_code error;
  fs::create_symlink(fs::absolute(target), link, error);
  if (error) fs::copy_file(target, link, fs::copy_options::overwrite_existing);
}

}  // namespace

int write_kidnapped_copy(const fs::path& source_dataset, const fs::path& dest_dataset, const KidnapPlan& plan) {
  const EurocSequence source = load_euroc_sequence(source_dataset);
  if (source.frames.empty()) throw std::runtime_error(source_dataset.string() + ": no stereo frames");
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
    for (std::size_t k = 0; k < source.frames.size(); ++k) {
      const std::int64_t stamp = source.frames[k].stamp_ns;
      const int index = static_cast<int>(k);
      if (index >= plan.black_first && index < plan.replay_first) {
        csv << stamp << ",black.png\n";
        continue;
      }
      std::size_t shown = k;
      if (index >= plan.replay_first) shown = static_cast<std::size_t>(plan.replay_source + index - plan.replay_first);
      if (shown >= source.frames.size()) break;
      const EurocFrame& image = source.frames[shown];
      const fs::path png = std::string(camera) == "cam0" ? image.left_png : image.right_png;
      const std::string name = std::to_string(stamp) + ".png";
      link_or_copy(png, dir / "data" / name);
      csv << stamp << ',' << name << '\n';
    }
  }
  if (fs::exists(source.mav0_dir / "body.yaml")) link_or_copy(source.mav0_dir / "body.yaml", mav0 / "body.yaml");
  return static_cast<int>(load_euroc_sequence(dest_dataset).frames.size());
}

}  // namespace heslam::bench
