// The vocabulary of the relocalization tests on images: the build's default one or, in a build that
// skipped training, a small one trained on the V101 clip's images (not MH01's nor the synthetic
// scenes': a test must not recognise places by having learnt their words).
#pragma once

#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "components/core/place/default_vocabulary.hpp"
#include "components/core/place/image_descriptors.hpp"
#include "components/core/place/vocabulary_io.hpp"
#include "components/core/place/vocabulary_training.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"

namespace heslam::test {

// Null when neither the default vocabulary nor the V101 clip is there (the caller skips).
inline std::shared_ptr<const Vocabulary> relocalization_test_vocabulary() {
  const auto path = default_vocabulary_path();
  if (std::filesystem::exists(path)) return std::make_shared<const Vocabulary>(load_vocabulary(path));
  if (shared_dataset("euroc_v101_head").empty()) return nullptr;
  std::printf("[ note     ] %s absent: training a small vocabulary on euroc_v101_head\n", path.c_str());
  const auto sequence = bench::load_euroc_sequence(shared_dataset("euroc_v101_head"));
  ImageDescriptorExtractor extractor;
  std::vector<std::vector<Descriptor>> images;
  for (std::size_t k = 0; k < sequence.frames.size(); k += 2) {
    images.push_back(extractor.extract(cv::imread(sequence.frames[k].left_png.string(), cv::IMREAD_GRAYSCALE)));
  }
  VocabularyTrainingOptions options;
  options.branching = 10;
  options.levels = 5;
  options.max_cluster_descriptors = 60000;
  return std::make_shared<const Vocabulary>(train_vocabulary(images, options));
}

}  // namespace heslam::test
