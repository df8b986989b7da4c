// Parsing heslam-vocab's arguments.
#include "tools/vocab/vocab_cli.hpp"

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "runtime/flags.hpp"
#include "runtime/quote_value.hpp"

namespace heslam::vocab {
namespace {

SynthSource parse_synth(const std::string& value) {
  SynthSource source;
  const std::size_t colon = value.find(':');
  source.preset = value.substr(0, colon);
  if (source.preset.empty()) runtime::throw_bad_flag_value("--synth", "PRESET[:SEED]", value);
  if (colon != std::string::npos) {
    std::int64_t seed = 0;
    if (!runtime::parse_whole_integer(value.substr(colon + 1), seed) || seed < 0) {
      runtime::throw_bad_flag_value("--synth", "PRESET[:SEED] with an integer SEED >= 0", value);
    }
    source.seed = static_cast<std::uint64_t>(seed);
  }
  return source;
}

constexpr int kMaxInt = std::numeric_limits<int>::max();
constexpr double kInfinity = std::numeric_limits<double>::infinity();

runtime::Flags train_flags(TrainOptions& o) {
  runtime::Flags flags(
      "heslam-vocab train [--images DIR...] [--dataset DIR...] [--synth PRESET[:SEED]...] --out FILE [options]");
  flags
      .custom("--images", "DIR...", "every *.jpg / *.png below, recursively",
              [&o](const std::string& value) { o.image_dirs.emplace_back(value); })
      .custom("--dataset", "DIR...", "EuRoC / KITTI folders: their left images",
              [&o](const std::string& value) { o.dataset_dirs.emplace_back(value); })
      .custom("--synth", "PRESET[:SEED]...", "synthetic sequences rendered on the fly",
              [&o](const std::string& value) { o.synth.push_back(parse_synth(value)); })
      .path("--out", "FILE", &o.out, "the vocabulary written (required)")
      .integer("--k", "K", &o.branching, 2, kMaxInt, "branching factor (10)")
      .integer("--levels", "L", &o.levels, 1, kMaxInt, "tree depth (6)")
      .integer("--features", "N", &o.features, 1, kMaxInt, "ORB features per image (1200)")
      .integer("--seed", "N", &o.seed, std::uint64_t{0}, std::numeric_limits<std::uint64_t>::max(), "k-means seed (1)")
      .integer("--threads", "N", &o.threads, 1, kMaxInt, "threads (2)")
      .integer("--max-descriptors", "N", &o.max_descriptors, std::size_t{0}, std::numeric_limits<std::size_t>::max(),
               "clustering sample, 0 = all (0)")
      .integer("--iterations", "N", &o.iterations, 1, kMaxInt, "k-means iterations (10)")
      .integer("--dataset-step", "N", &o.dataset_step, 1, kMaxInt, "every Nth dataset frame (10)")
      .integer("--synth-step", "N", &o.synth_step, 1, kMaxInt, "every Nth rendered frame (10)")
      .integer("--min-features", "N", &o.min_features, 0, kMaxInt,
               "images with fewer descriptors (masks, plots) are skipped (100)");
  return flags;
}

runtime::Flags score_flags(ScoreOptions& o) {
  runtime::Flags flags("heslam-vocab score --dataset DIR [options]");
  flags.path("--dataset", "DIR", &o.dataset, "the sequence with ground truth (required)")
      .path("--vocabulary", "FILE", &o.vocabulary, "default: the build's vocabulary")
      .integer("--step", "N", &o.step, 1, kMaxInt, "every Nth frame is a query / candidate (5)")
      .number("--exclude-recent-s", "S", &o.exclude_recent_s, 0.0, kInfinity, "candidates are older than this (10)")
      .number("--max-distance-m", "M", &o.max_distance_m, 0.0, kInfinity, "a true match is this close (1)")
      .number("--max-angle-deg", "DEG", &o.max_angle_deg, 0.0, kInfinity, "... and looks within this angle (30)")
      .integer("--features", "N", &o.features, 1, kMaxInt, "ORB features per image (1200)")
      .toggle("--verbose", &o.verbose, "one line per query");
  return flags;
}

// "--images A B --out F" is "--images A --images B --out F": the multi-value flags take every
// argument up to the next flag.
std::vector<std::string> expand_multi_value_flags(const std::vector<std::string>& args) {
  std::vector<std::string> out;
  std::string multi;       // the multi-value flag whose values are being read ("" : none)
  bool own_value = false;  // the next argument is the flag's own value
  for (const std::string& arg : args) {
    if (arg.starts_with("--")) {
      multi = arg == "--images" || arg == "--dataset" || arg == "--synth" ? arg : "";
      own_value = true;
    } else {
      if (!multi.empty() && !own_value) out.push_back(multi);
      own_value = false;
    }
    out.push_back(arg);
  }
  return out;
}

}  // namespace

std::string usage() {
  TrainOptions train;
  ScoreOptions score;
  return train_flags(train).usage() +
         "usage: heslam-vocab convert IN OUT      (OUT ending in .txt: DBoW2 text, else heslam binary)\n"
         "usage: heslam-vocab info FILE\n" +
         score_flags(score).usage() +
         "Files of either format are recognised by content. The default vocabulary is the build's\n"
         "vocabulary/heslam_orb.hvoc (docs/place_recognition.md).\n";
}

Cli parse_cli(int argc, char** argv) {
  Cli cli;
  if (argc < 2) throw std::runtime_error("no command given\n" + usage());
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  for (const std::string& arg : std::vector<std::string>(argv + 1, argv + argc)) {
    if (arg == "--help" || arg == "-h") return cli;
  }
  if (command == "train") {
    cli.command = Command::kTrain;
    train_flags(cli.train).parse(expand_multi_value_flags(args));
    if (cli.train.out.empty()) throw std::runtime_error("train: --out FILE is required");
    if (cli.train.image_dirs.empty() && cli.train.dataset_dirs.empty() && cli.train.synth.empty()) {
      throw std::runtime_error("train: give at least one of --images, --dataset, --synth");
    }
  } else if (command == "score") {
    cli.command = Command::kScore;
    score_flags(cli.score).parse(args);
    if (cli.score.dataset.empty()) throw std::runtime_error("score: --dataset DIR is required");
  } else if (command == "convert" || command == "info") {
    cli.command = command == "convert" ? Command::kConvert : Command::kInfo;
    runtime::Flags flags("heslam-vocab " + command + (command == "convert" ? " IN OUT" : " FILE"));
    flags.positional("FILE", "", [&cli](const std::string& arg) { cli.files.emplace_back(arg); });
    flags.parse(args);
    const std::size_t wanted = cli.command == Command::kConvert ? 2 : 1;
    if (cli.files.size() != wanted) {
      throw std::runtime_error(command + (wanted == 2 ? " expects IN OUT" : " expects FILE") + ", got " +
                               std::to_string(cli.files.size()) + " arguments");
    }
  } else {
    throw std::runtime_error("unknown command '" + runtime::quote_value(command) +
                             "' (train, convert, info, score; --help)");
  }
  return cli;
}

}  // namespace heslam::vocab
