// The descriptors heslam-vocab trains on: photographs in folders, left images of recorded datasets,
// frames rendered by heslam-synth; each image through the frontend's HE + ORB.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "components/core/feature/features.hpp"
#include "tools/vocab/vocab_cli.hpp"

namespace heslam::vocab {

struct TrainingSet {
  std::vector<std::vector<Descriptor>> images;  // per kept image
  int skipped_images = 0;                       // fewer than min_features descriptors
  std::size_t descriptor_count = 0;
};

// Image files and dataset frames are read in sorted order, so the set is the same on every run.
// Throws std::runtime_error naming the folder or file that cannot be read.
TrainingSet collect_training_set(const TrainOptions& options, const std::function<void(const std::string&)>& progress);

}  // namespace heslam::vocab
