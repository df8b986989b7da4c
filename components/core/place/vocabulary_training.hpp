// Training a vocabulary tree from the descriptors of many images: hierarchical k-medians (k-means++
// seeding, bitwise-majority medians for binary descriptors), then word weights from the images
// (IDF = log(images / images containing the word)). Deterministic for a seed and any thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "components/core/feature/features.hpp"
#include "components/core/place/vocabulary.hpp"

namespace heslam {

struct VocabularyTrainingOptions {
  int branching = 10;  // k (ORBvoc.txt: 10)
  int levels = 6;      // L (ORBvoc.txt: 6): up to k^L words
  BowWeighting weighting = BowWeighting::kTfIdf;
  BowScoring scoring = BowScoring::kL1;
  std::uint64_t seed = 1;
  int threads = 1;                 // subtrees are clustered in parallel; the result does not depend on it
  int max_iterations = 10;         // k-medians iterations per node (stops earlier when stable)
  // Called with one line now and then on long runs (e.g. "level 3/6: 412 nodes"); may be empty.
  std::function<void(const std::string&)> progress;
};

// `images[i]` are the descriptors of training image i (the IDF counts images). Throws
// std::invalid_argument when there are no descriptors or the options are out of range.
Vocabulary train_vocabulary(const std::vector<std::vector<Descriptor>>& images,
                            const VocabularyTrainingOptions& options);

}  // namespace heslam
