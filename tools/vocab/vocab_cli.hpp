// heslam-vocab's command line: the four commands and their options.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace heslam::vocab {

enum class Command { kHelp, kTrain, kConvert, kInfo, kScore };

// A synthetic sequence rendered for training: heslam-synth's preset with its own seed.
struct SynthSource {
  std::string preset;
  std::uint64_t seed = 1000;
};

struct TrainOptions {
  std::vector<std::filesystem::path> image_dirs;    // every *.jpg / *.png below, recursively
  std::vector<std::filesystem::path> dataset_dirs;  // EuRoC / KITTI folders: left images
  std::vector<SynthSource> synth;
  std::filesystem::path out;
  int branching = 10;
  int levels = 6;
  int features = 1200;
  std::uint64_t seed = 1;
  int threads = 2;
  int iterations = 10;
  std::size_t max_descriptors = 0;  // clustering sample, 0 = all
  int dataset_step = 10;            // every Nth dataset frame
  int synth_step = 10;              // every Nth rendered frame
  int min_features = 100;           // images with fewer descriptors (masks, plots) are skipped
};

struct ScoreOptions {
  std::filesystem::path dataset;
  std::filesystem::path vocabulary;  // empty: the default vocabulary
  int step = 5;                      // every Nth frame is a query / candidate
  double exclude_recent_s = 10.0;    // candidates are older than this
  double max_distance_m = 1.0;       // ground truth: a true match is this close
  double max_angle_deg = 30.0;       // ... and looks within this angle
  int features = 1200;
  bool verbose = false;  // one line per query
};

struct Cli {
  Command command = Command::kHelp;
  TrainOptions train;
  ScoreOptions score;
  std::vector<std::filesystem::path> files;  // convert: IN OUT; info: FILE
};

std::string usage();

// Throws std::runtime_error with one line naming the flag and what it expected.
Cli parse_cli(int argc, char** argv);

}  // namespace heslam::vocab
