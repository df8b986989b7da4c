// Parsing heslam-vocab's arguments.
#include "tools/vocab/vocab_cli.hpp"

#include <charconv>
#include <stdexcept>
#include <string_view>

namespace heslam::vocab {
namespace {

constexpr const char* kUsage =
    "usage: heslam-vocab train [--images DIR...] [--dataset DIR...] [--synth PRESET[:SEED]...] --out FILE\n"
    "                          [--k 10] [--levels 6] [--features 1200] [--seed 1] [--threads 2]\n"
    "                          [--max-descriptors N] [--iterations 10] [--dataset-step 10] [--synth-step 10]\n"
    "                          [--min-features 100]\n"
    "       heslam-vocab convert IN OUT      (OUT ending in .txt: DBoW2 text, else heslam binary)\n"
    "       heslam-vocab info FILE\n"
    "       heslam-vocab score --dataset DIR [--vocabulary FILE] [--step 5] [--exclude-recent-s 10]\n"
    "                          [--max-distance-m 1] [--max-angle-deg 30] [--features 1200] [--verbose]\n"
    "Files of either format are recognised by content. The default vocabulary is the build's\n"
    "vocabulary/heslam_orb.hvoc (docs/place_recognition.md).\n";

template <typename T>
T parse_number(const std::string& flag, const std::string& value, T min) {
  T parsed{};
  const auto [ptr, ec] = std::from_chars(value.data(), value.data() + value.size(), parsed);
  if (ec != std::errc() || ptr != value.data() + value.size() || parsed < min) {
    throw std::runtime_error(flag + " expects a number >= " + std::to_string(min) + ", got '" + value + "'");
  }
  return parsed;
}

SynthSource parse_synth(const std::string& value) {
  SynthSource source;
  const std::size_t colon = value.find(':');
  source.preset = value.substr(0, colon);
  if (source.preset.empty()) throw std::runtime_error("--synth expects PRESET[:SEED], got '" + value + "'");
  if (colon != std::string::npos) source.seed = parse_number<std::uint64_t>("--synth seed", value.substr(colon + 1), 0);
  return source;
}

class Args {
 public:
  Args(int argc, char** argv, int first) : argc_(argc), argv_(argv), i_(first) {}
  bool done() const { return i_ >= argc_; }
  std::string next() { return argv_[i_++]; }
  std::string value(const std::string& flag) {
    if (done() || std::string_view(argv_[i_]).starts_with("--")) throw std::runtime_error(flag + " needs a value");
    return next();
  }
  // One or more values up to the next flag.
  std::vector<std::string> values(const std::string& flag) {
    std::vector<std::string> out{value(flag)};
    while (!done() && !std::string_view(argv_[i_]).starts_with("--")) out.push_back(next());
    return out;
  }

 private:
  int argc_;
  char** argv_;
  int i_;
};

void parse_train(Args& args, TrainOptions& o) {
  while (!args.done()) {
    const std::string flag = args.next();
    if (flag == "--images") for (const auto& v : args.values(flag)) o.image_dirs.emplace_back(v);
    else if (flag == "--dataset") for (const auto& v : args.values(flag)) o.dataset_dirs.emplace_back(v);
    else if (flag == "--synth") for (const auto& v : args.values(flag)) o.synth.push_back(parse_synth(v));
    else if (flag == "--out") o.out = args.value(flag);
    else if (flag == "--k") o.branching = parse_number<int>(flag, args.value(flag), 2);
    else if (flag == "--levels") o.levels = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--features") o.features = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--seed") o.seed = parse_number<std::uint64_t>(flag, args.value(flag), 0);
    else if (flag == "--threads") o.threads = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--iterations") o.iterations = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--max-descriptors") o.max_descriptors = parse_number<std::size_t>(flag, args.value(flag), 0);
    else if (flag == "--dataset-step") o.dataset_step = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--synth-step") o.synth_step = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--min-features") o.min_features = parse_number<int>(flag, args.value(flag), 0);
    else throw std::runtime_error("train: unknown argument '" + flag + "' (heslam-vocab --help)");
  }
  if (o.out.empty()) throw std::runtime_error("train: --out FILE is required");
  if (o.image_dirs.empty() && o.dataset_dirs.empty() && o.synth.empty()) {
    throw std::runtime_error("train: give at least one of --images, --dataset, --synth");
  }
}

void parse_score(Args& args, ScoreOptions& o) {
  while (!args.done()) {
    const std::string flag = args.next();
    if (flag == "--dataset") o.dataset = args.value(flag);
    else if (flag == "--vocabulary") o.vocabulary = args.value(flag);
    else if (flag == "--step") o.step = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--exclude-recent-s") o.exclude_recent_s = parse_number<double>(flag, args.value(flag), 0.0);
    else if (flag == "--max-distance-m") o.max_distance_m = parse_number<double>(flag, args.value(flag), 0.0);
    else if (flag == "--max-angle-deg") o.max_angle_deg = parse_number<double>(flag, args.value(flag), 0.0);
    else if (flag == "--features") o.features = parse_number<int>(flag, args.value(flag), 1);
    else if (flag == "--verbose") o.verbose = true;
    else throw std::runtime_error("score: unknown argument '" + flag + "' (heslam-vocab --help)");
  }
  if (o.dataset.empty()) throw std::runtime_error("score: --dataset DIR is required");
}

}  // namespace

const char* usage() { return kUsage; }

Cli parse_cli(int argc, char** argv) {
  Cli cli;
  if (argc < 2) throw std::runtime_error(std::string("no command given\n") + kUsage);
  const std::string command = argv[1];
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--help" || arg == "-h") return cli;
  }
  Args args(argc, argv, 2);
  if (command == "train") {
    cli.command = Command::kTrain;
    parse_train(args, cli.train);
  } else if (command == "score") {
    cli.command = Command::kScore;
    parse_score(args, cli.score);
  } else if (command == "convert" || command == "info") {
    cli.command = command == "convert" ? Command::kConvert : Command::kInfo;
    while (!args.done()) cli.files.emplace_back(args.next());
    const std::size_t wanted = cli.command == Command::kConvert ? 2 : 1;
    if (cli.files.size() != wanted) {
      throw std::runtime_error(command + (wanted == 2 ? " expects IN OUT" : " expects FILE") + ", got " +
                               std::to_string(cli.files.size()) + " arguments");
    }
  } else {
    throw std::runtime_error("unknown command '" + command + "' (train, convert, info, score; --help)");
  }
  return cli;
}

}  // namespace heslam::vocab
