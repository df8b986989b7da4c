// Copies a dataset folder file by file, transforming the images of its stereo pairs on the way.
#include "tools/photometric/dataset_copy.hpp"

#include <map>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace heslam::photometric {

namespace fs = std::filesystem;

namespace {

constexpr int kSaturatedGrey = 255;

// Where a frame's image goes: its path relative to the input folder, joined to the output folder.
struct PairTarget {
  std::size_t frame_index = 0;
  bool right = false;
};

fs::path relative_inside(const fs::path& file, const fs::path& root) {
  const fs::path relative = fs::weakly_canonical(file).lexically_relative(root);
  if (relative.empty() || *relative.begin() == "..") {
    throw std::runtime_error(file.string() + ": a frame's image lies outside the dataset folder " + root.string() +
                             " (cannot place it in the copy)");
  }
  return relative;
}

cv::Mat read_grey(const fs::path& file) {
  cv::Mat image = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error(file.string() + ": cannot read the image (missing or not an image)");
  return image;
}

void write_image(const fs::path& file, const cv::Mat& image) {
  fs::create_directories(file.parent_path());
  bool written = false;
  try {
    written = cv::imwrite(file.string(), image);
  } catch (const cv::Exception&) {
    written = false;
  }
  if (!written) throw std::runtime_error(file.string() + ": cannot write the transformed image");
}

double saturated_share(const cv::Mat& image) {
  return static_cast<double>(cv::countNonZero(image >= kSaturatedGrey)) / static_cast<double>(image.total());
}

// Removes a half-written copy unless released (the copy finished).
class OutputGuard {
 public:
  explicit OutputGuard(fs::path output) : output_(std::move(output)) {}
  OutputGuard(const OutputGuard&) = delete;
  OutputGuard& operator=(const OutputGuard&) = delete;
  ~OutputGuard() {
    if (armed_) {
      std::error_code ignored;
      fs::remove_all(output_, ignored);
    }
  }
  void release() { armed_ = false; }

 private:
  fs::path output_;
  bool armed_ = true;
};

}  // namespace

DatasetCopySummary write_dataset_copy(const fs::path& input, const fs::path& output,
                                      const DatasetCopyOptions& options) {
  DatasetOptions dataset_options;
  dataset_options.format = options.format;
  const StereoDataset dataset = open_dataset(input, dataset_options);
  if (dataset.frames.empty()) throw std::runtime_error(input.string() + ": no stereo pairs to transform");

  const fs::path input_root = fs::weakly_canonical(input);
  const fs::path output_root = fs::weakly_canonical(output);
  const fs::path output_in_input = output_root.lexically_relative(input_root);
  if (output_root == input_root || (!output_in_input.empty() && *output_in_input.begin() != "..")) {
    throw std::runtime_error(output.string() + ": the output folder must not be (inside) the input folder " +
                             input.string());
  }
  if (fs::exists(output) && (!fs::is_directory(output) || !fs::is_empty(output))) {
    throw std::runtime_error(output.string() + ": exists and is not an empty folder (refusing to overwrite it)");
  }

  std::map<fs::path, PairTarget> images;  // relative path -> which image of which pair
  for (std::size_t k = 0; k < dataset.frames.size(); ++k) {
    images[relative_inside(dataset.frames[k].left, input_root)] = {k, false};
    images[relative_inside(dataset.frames[k].right, input_root)] = {k, true};
  }

  fs::create_directories(output);
  OutputGuard guard(output);
  DatasetCopySummary summary;
  summary.format = dataset.format;
  for (const fs::directory_entry& entry :
       fs::recursive_directory_iterator(input_root, fs::directory_options::follow_directory_symlink)) {
    const fs::path relative = entry.path().lexically_relative(input_root);
    if (entry.is_directory()) {
      fs::create_directories(output_root / relative);
    } else if (images.count(relative) == 0) {
      fs::create_directories((output_root / relative).parent_path());
      fs::copy_file(entry.path(), output_root / relative);  // follows symlinks: the copy stands alone
      ++summary.copied_files;
    }
  }
  const std::size_t count = dataset.frames.size();
  for (std::size_t k = 0; k < count; ++k) {
    const StereoFrameFiles& frame = dataset.frames[k];
    cv::Mat left = read_grey(frame.left);
    cv::Mat right = read_grey(frame.right);
    apply_to_pair(left, right, options.variant, stereo_gain_at(options.stereo_gain, k, count), k);
    summary.left_saturated_share += saturated_share(left);
    summary.right_saturated_share += saturated_share(right);
    write_image(output_root / relative_inside(frame.left, input_root), left);
    write_image(output_root / relative_inside(frame.right, input_root), right);
  }
  summary.frames = count;
  summary.left_saturated_share /= static_cast<double>(count);
  summary.right_saturated_share /= static_cast<double>(count);
  guard.release();
  return summary;
}

}  // namespace heslam::photometric
