// heslam-vocab: trains ORB vocabularies, converts between DBoW2 text and heslam binary, describes
// a vocabulary file, and scores place recognition on a dataset with ground truth.
#include <chrono>
#include <cstdio>
#include <exception>
#include <iostream>

#include "components/core/place/default_vocabulary.hpp"
#include "components/core/place/vocabulary_io.hpp"
#include "components/core/place/vocabulary_training.hpp"
#include "tools/vocab/place_score.hpp"
#include "tools/vocab/training_images.hpp"
#include "tools/vocab/vocab_cli.hpp"

namespace {

using namespace heslam;
using namespace heslam::vocab;
namespace fs = std::filesystem;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void save(const fs::path& path, const Vocabulary& vocabulary) {
  if (path.extension() == ".txt")
    save_vocabulary_text(path, vocabulary);
  else
    save_vocabulary_binary(path, vocabulary);
}

void progress_line(const std::string& line) { std::cerr << "heslam-vocab: " << line << "\n"; }

int train(const TrainOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const TrainingSet set = collect_training_set(options, progress_line);
  progress_line("extracted " + std::to_string(set.descriptor_count) + " descriptors from " +
                std::to_string(set.images.size()) + " images (" + std::to_string(set.skipped_images) + " skipped, < " +
                std::to_string(options.min_features) + " features) in " + std::to_string(seconds_since(start)) + " s");
  VocabularyTrainingOptions training;
  training.branching = options.branching;
  training.levels = options.levels;
  training.seed = options.seed;
  training.threads = options.threads;
  training.max_iterations = options.iterations;
  training.max_cluster_descriptors = options.max_descriptors;
  training.progress = progress_line;
  const auto train_start = std::chrono::steady_clock::now();
  const Vocabulary vocabulary = train_vocabulary(set.images, training);
  const double train_s = seconds_since(train_start);
  if (options.out.has_parent_path()) fs::create_directories(options.out.parent_path());
  save(options.out, vocabulary);
  std::printf("wrote %s: %zu words, %zu nodes, k %d, L %d (clustering + weights %.1f s, total %.1f s)\n",
              options.out.c_str(), vocabulary.word_count(), vocabulary.node_count(), vocabulary.branching(),
              vocabulary.levels(), train_s, seconds_since(start));
  return 0;
}

int convert(const fs::path& in, const fs::path& out) {
  const auto start = std::chrono::steady_clock::now();
  const Vocabulary vocabulary = load_vocabulary(in);
  const double load_s = seconds_since(start);
  save(out, vocabulary);
  std::printf("%s (%.2f s) -> %s (%s, %.2f s): %zu words\n", in.c_str(), load_s, out.c_str(),
              out.extension() == ".txt" ? "DBoW2 text" : "heslam binary", seconds_since(start) - load_s,
              vocabulary.word_count());
  return 0;
}

int info(const fs::path& path) {
  const auto start = std::chrono::steady_clock::now();
  const Vocabulary vocabulary = load_vocabulary(path);
  const double load_s = seconds_since(start);
  const auto records = vocabulary.node_records();
  std::vector<int> depth(records.size() + 1, 0);
  int max_depth = 0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    depth[i + 1] = depth[records[i].parent] + 1;
    max_depth = std::max(max_depth, depth[i + 1]);
  }
  double weight_sum = 0.0;
  std::size_t zero_weight = 0;
  for (WordId w = 0; w < vocabulary.word_count(); ++w) {
    weight_sum += vocabulary.word_weight(w);
    zero_weight += vocabulary.word_weight(w) == 0.f ? 1 : 0;
  }
  const bool binary = detect_vocabulary_format(path) == VocabularyFileFormat::kHeslamBinary;
  std::printf("file:      %s (%s, %.1f MB, loaded in %.3f s)\n", path.c_str(), binary ? "heslam binary" : "DBoW2 text",
              fs::file_size(path) / 1e6, load_s);
  std::printf("tree:      k %d, L %d (deepest leaf at %d), %zu nodes, %zu words\n", vocabulary.branching(),
              vocabulary.levels(), max_depth, vocabulary.node_count(), vocabulary.word_count());
  std::printf("weighting: %s, scoring: %s\n", to_string(vocabulary.weighting()), to_string(vocabulary.scoring()));
  std::printf("weights:   mean %.3f, %zu words with weight 0 (in every training image; ignored by BoW)\n",
              vocabulary.word_count() ? weight_sum / vocabulary.word_count() : 0.0, zero_weight);
  return 0;
}

int score(const ScoreOptions& options) {
  const fs::path path = options.vocabulary.empty() ? default_vocabulary_path() : options.vocabulary;
  const Vocabulary vocabulary = load_vocabulary(path);
  const ScoreSummary s = score_dataset(options, vocabulary, std::cout);
  std::printf("dataset:    %s, %d frames scored (every %d), candidates older than %.1f s\n", options.dataset.c_str(),
              s.frames, options.step, options.exclude_recent_s);
  std::printf("vocabulary: %s (%zu words), transform %.2f ms per frame\n", path.c_str(), vocabulary.word_count(),
              s.mean_transform_ms);
  std::printf("queries:    %d with candidates, %d revisit a place (an earlier frame within %.1f m and %.0f deg)\n",
              s.queries, s.revisits, options.max_distance_m, options.max_angle_deg);
  std::printf("top candidate, all accepted: precision %.3f (%d/%d), recall %.3f (%d/%d)\n", s.precision_all, s.correct,
              s.queries, s.recall_all, s.correct, s.revisits);
  std::printf("top candidate at precision 1: recall %.3f (score >= %.4f)\n", s.recall_at_precision_1,
              s.threshold_at_precision_1);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Cli cli = parse_cli(argc, argv);
    switch (cli.command) {
      case Command::kHelp: std::cout << usage(); return 0;
      case Command::kTrain: return train(cli.train);
      case Command::kConvert: return convert(cli.files[0], cli.files[1]);
      case Command::kInfo: return info(cli.files[0]);
      case Command::kScore: return score(cli.score);
    }
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "heslam-vocab: " << e.what() << "\n";
    return 1;
  }
}
