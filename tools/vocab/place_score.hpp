// heslam-vocab score: a quick place-recognition check of a vocabulary on a dataset with ground truth.
// Each query frame's best-scoring earlier frame (older than exclude_recent_s) is its top candidate;
// it is correct when the two cameras are within max_distance_m and their optical axes within
// max_angle_deg. Precision / recall of the top candidate over a sweep of the score threshold.
#pragma once

#include <ostream>

#include "components/core/place/vocabulary.hpp"
#include "tools/vocab/vocab_cli.hpp"

namespace heslam::vocab {

struct ScoreSummary {
  int frames = 0;                    // frames scored (every step-th)
  int queries = 0;                   // frames with at least one candidate
  int revisits = 0;                  // queries with a true match among their candidates
  int correct = 0;                   // queries whose top candidate is a true match
  double precision_all = 0;          // correct / queries (every top candidate accepted)
  double recall_all = 0;             // correct / revisits
  double recall_at_precision_1 = 0;  // best recall with no wrong accepted candidate
  double threshold_at_precision_1 = 0;
  double mean_transform_ms = 0;
};

// Throws std::runtime_error naming the file when the dataset or its ground truth cannot be read.
ScoreSummary score_dataset(const ScoreOptions& options, const Vocabulary& vocabulary, std::ostream& out);

}  // namespace heslam::vocab
