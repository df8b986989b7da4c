// Two agents on one map end to end (docs/agents.md): config/pipelines/euroc_two_agents.yaml (two replays,
// two frontends, one local mapper, one loop closer, a recorder per agent, lockstep with turns) on the
// shared MH01 clip split in two overlapping halves made here: agent a plays frames 0-99, agent b frames
// 60-159 (a copy of the dataset with a subset of the frame list and its ground truth). The replays take
// turns in stamp order, so agent b starts at agent a's frame 60, and both see the same part of the hall.
// Known answers from the ground truth: every frame of both agents has a pose, the loop closer merges the
// two maps once, within 10 frames of agent b's start (the issue's bar), after which every pose of both
// agents is in one map (no STEM.a.maps.txt / STEM.b.maps.txt: the recorders saw one map id in the end), and
// both trajectories are in one frame: aligned to the ground truth ONCE (one SE(3) for the poses of both),
// each agent's ATE is <= 5 mm. Ids: agent b's keyframes carry its agent (ids.hpp), the mapper and the loop
// closer refuse nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFirstA = 0;   // agent a: frames 0-99 of the clip
constexpr int kFirstB = 60;  // agent b: frames 60-159
constexpr int kFramesPerAgent = 100;
// The issue's bar: a merge within 10 frames of b's start. Measured (docs/agents.md): at b's frame 6 (b's third
// keyframe recognises a's keyframe of the clip's frame 59, 138 matches).
constexpr int kMaxMergeDelayFrames = 10;
constexpr double kMaxAteM = 0.005;  // the issue's bar: ATE of each agent <= 5 mm
constexpr double kRateHz = 20.0;
constexpr std::chrono::seconds kRunTimeout{900};

// The data rows (not the header) of a CSV file.
std::vector<std::string> rows(const fs::path& path, std::string* header) {
  std::ifstream in(path);
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      *header = line;
      continue;
    }
    out.push_back(line);
  }
  return out;
}

void write_rows(const fs::path& path, const std::string& header, const std::vector<std::string>& all, int first,
                int count) {
  std::ofstream out(path);
  out << header << "\n";
  for (int i = first; i < first + count; ++i) out << all.at(static_cast<std::size_t>(i)) << "\n";
}

// A copy of the EuRoC folder `source` with frames [first, first + count) of its frame lists and ground
// truth (images linked, not copied).
void make_part(const fs::path& source, const fs::path& part, int first, int count) {
  for (const char* camera : {"cam0", "cam1"}) {
    const fs::path from = source / "mav0" / camera;
    const fs::path to = part / "mav0" / camera;
    fs::create_directories(to);
    fs::create_symlink(from / "data", to / "data");
    fs::copy_file(from / "sensor.yaml", to / "sensor.yaml");
    std::string header;
    const std::vector<std::string> frames = rows(from / "data.csv", &header);
    write_rows(to / "data.csv", header, frames, first, count);
  }
  fs::copy_file(source / "mav0/body.yaml", part / "mav0/body.yaml");
  const fs::path truth = "mav0/state_groundtruth_estimate0";
  fs::create_directories(part / truth);
  std::string header;
  const std::vector<std::string> poses = rows(source / truth / "data.csv", &header);
  write_rows(part / truth / "data.csv", header, poses, first, count);
}

// The loop closer's merge lines: the stamp (s) of the keyframe at which each merge happened.
std::vector<double> merge_stamps_s(const std::string& output) {
  static const std::regex line(R"(maps merged: map \d+ into map \d+ at keyframe \S+ \(stamp ([0-9.]+) s\))");
  std::vector<double> stamps;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    stamps.push_back(std::stod((*it)[1]));
  }
  return stamps;
}

TEST(TwoAgentsEndToEnd, Mh01HalvesMergeIntoOneFrame) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path clip = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("two_agents");
  const fs::path half_a = dir.path() / "half_a";
  const fs::path half_b = dir.path() / "half_b";
  make_part(clip, half_a, kFirstA, kFramesPerAgent);
  make_part(clip, half_b, kFirstB, kFramesPerAgent);

  const std::string label = "agents";
  test::ChildProcess supervisor(
      test::bin_dir() / "heslam-supervisor",
      {(test::source_dir() / "config/pipelines/euroc_two_agents.yaml").string(), "--domain",
       std::to_string(test::exclusive_domain_id()), "--log-dir", (dir.path() / "logs").string(), "--arg",
       "dataset_a=" + half_a.string(), "--arg", "dataset_b=" + half_b.string(), "--arg",
       "output=" + (dir.path() / (label + ".txt")).string()},
      dir.path(), "supervisor_" + label);
  const int code = test::finish(supervisor, kRunTimeout);
  const std::string output = supervisor.out() + supervisor.err();
  ASSERT_EQ(code, 0) << output;

  const eval::Trajectory a = eval::read_trajectory(dir.path() / (label + ".a.txt"));
  const eval::Trajectory b = eval::read_trajectory(dir.path() / (label + ".b.txt"));
  EXPECT_EQ(a.size(), static_cast<std::size_t>(kFramesPerAgent));
  EXPECT_EQ(b.size(), static_cast<std::size_t>(kFramesPerAgent));

  // One merge, within 10 frames of b's start (20 Hz: b's frame k has stamp b's first + k / 20 s).
  const std::vector<double> merged_at_s = merge_stamps_s(output);
  ASSERT_EQ(merged_at_s.size(), 1u) << output;
  const long merge_frame_of_b = std::lround((merged_at_s[0] - b.stamps_s.front()) * kRateHz);

  // One alignment for both agents: their pairs with the ground truth together.
  eval::AlignedPair pair_a = eval::associate(test::ground_truth_for(half_a, a), a);
  eval::AlignedPair pair_b = eval::associate(test::ground_truth_for(half_b, b), b);
  eval::AlignedPair both = pair_a;
  for (std::size_t i = 0; i < pair_b.size(); ++i) {
    both.gt.push_back(pair_b.gt.poses_wc[i], pair_b.gt.frame_ids[i], pair_b.gt.stamps_s[i]);
    both.est.push_back(pair_b.est.poses_wc[i], pair_b.est.frame_ids[i], pair_b.est.stamps_s[i]);
  }
  const eval::ApeResult ape = eval::compute_ape(both);
  double sum_a = 0.0, sum_b = 0.0;
  for (std::size_t i = 0; i < ape.translation_errors_m.size(); ++i) {
    const double e2 = ape.translation_errors_m[i] * ape.translation_errors_m[i];
    (i < pair_a.size() ? sum_a : sum_b) += e2;
  }
  const double ate_a = std::sqrt(sum_a / static_cast<double>(pair_a.size()));
  const double ate_b = std::sqrt(sum_b / static_cast<double>(pair_b.size()));
  const double alone_a = eval::compute_ape(pair_a).translation_m.rmse;
  const double alone_b = eval::compute_ape(pair_b).translation_m.rmse;
  std::printf(
      "[ figures  ] MH01 halves as two agents: ATE in one frame a %.2f mm, b %.2f mm (each aligned alone: %.2f, "
      "%.2f mm); merged at agent b's frame %ld\n",
      ate_a * 1e3, ate_b * 1e3, alone_a * 1e3, alone_b * 1e3, merge_frame_of_b);
  EXPECT_LE(merge_frame_of_b, kMaxMergeDelayFrames);
  EXPECT_LE(ate_a, kMaxAteM);
  EXPECT_LE(ate_b, kMaxAteM);
  EXPECT_EQ(output.find("refused_agent_keyframes"), std::string::npos) << output;
  // One map in the end: b's map renumbered by the merge, none started again by a keyframe made with its old id.
  EXPECT_FALSE(fs::exists(dir.path() / (label + ".a.maps.txt")));
  EXPECT_FALSE(fs::exists(dir.path() / (label + ".b.maps.txt")));
}

}  // namespace
}  // namespace heslam
