// Gathering training descriptors from image folders, datasets and synthetic renders.
#include "tools/vocab/training_images.hpp"

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <thread>

#include <opencv2/imgcodecs.hpp>

#include "components/core/place/image_descriptors.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/sequence.hpp"

namespace heslam::vocab {
namespace {

namespace fs = std::filesystem;

bool is_image_file(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

std::vector<fs::path> image_files(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw std::runtime_error("--images " + dir.string() + ": not a folder");
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file() && is_image_file(entry.path())) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error("--images " + dir.string() + ": no .png / .jpg files");
  return files;
}

OrbOptions orb_options(int features) {
  OrbOptions orb;
  orb.features = features;
  return orb;
}

class Collector {
 public:
  Collector(const TrainOptions& options, const std::function<void(const std::string&)>& progress)
      : options_(options), progress_(progress) {}

  void add(std::vector<Descriptor> descriptors) {
    if (static_cast<int>(descriptors.size()) < options_.min_features) {
      ++set_.skipped_images;
      return;
    }
    set_.descriptor_count += descriptors.size();
    set_.images.push_back(std::move(descriptors));
  }

  // Files decoded and extracted on options.threads threads, added in list order.
  void add_files(const std::vector<fs::path>& files, const std::string& label) {
    std::vector<std::vector<Descriptor>> results(files.size());
    std::atomic<std::size_t> next{0};
    std::atomic<std::size_t> done{0};
    std::string error;
    std::atomic<bool> failed{false};
    auto work = [&] {
      ImageDescriptorExtractor extractor({}, orb_options(options_.features));
      for (std::size_t i = next++; i < files.size() && !failed; i = next++) {
        const cv::Mat image = cv::imread(files[i].string(), cv::IMREAD_GRAYSCALE);
        if (image.empty()) {
          if (!failed.exchange(true)) error = files[i].string() + ": cannot decode image";
          return;
        }
        results[i] = extractor.extract(image);
        ++done;
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < options_.threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
    if (failed) throw std::runtime_error(error);
    for (auto& r : results) add(std::move(r));
    report(label + ": " + std::to_string(files.size()) + " images");
  }

  void add_synth(const SynthSource& source) {
    synth::RenderOptions render;
    render.seed = source.seed;
    render.threads = std::min(options_.threads, 2);
    synth::SequenceRenderer renderer(synth::load_preset(synth::find_preset(source.preset)), render);
    ImageDescriptorExtractor extractor({}, orb_options(options_.features));
    int frames = 0;
    for (int i = 0; i < renderer.num_frames(); i += options_.synth_step, ++frames) {
      add(extractor.extract(renderer.render_frame(i).left));
    }
    report("synth " + source.preset + " (seed " + std::to_string(source.seed) + "): " + std::to_string(frames) +
           " frames");
  }

  void report(const std::string& what) {
    if (progress_) {
      progress_(what + ", " + std::to_string(set_.images.size()) + " images / " +
                std::to_string(set_.descriptor_count) + " descriptors so far");
    }
  }

  TrainingSet take() { return std::move(set_); }

 private:
  const TrainOptions& options_;
  const std::function<void(const std::string&)>& progress_;
  TrainingSet set_;
};

}  // namespace

TrainingSet collect_training_set(const TrainOptions& options, const std::function<void(const std::string&)>& progress) {
  Collector collector(options, progress);
  for (const fs::path& dir : options.image_dirs) collector.add_files(image_files(dir), dir.string());
  for (const fs::path& dir : options.dataset_dirs) {
    const StereoDataset dataset = open_dataset(dir);
    std::vector<fs::path> files;
    for (std::size_t i = 0; i < dataset.frames.size(); i += options.dataset_step)
      files.push_back(dataset.frames[i].left);
    collector.add_files(files, dir.string());
  }
  for (const SynthSource& source : options.synth) collector.add_synth(source);
  return collector.take();
}

}  // namespace heslam::vocab
