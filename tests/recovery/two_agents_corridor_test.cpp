// Two agents starting at opposite ends of a loop (issue 37's second two-agent case, docs/agents.md):
// heslam-synth's corridor_loop as the suite renders it (build/test-data/corridor_loop_880: once round the
// 42 m ring and just past the start) split in two halves made here: agent a plays frames 0-439, agent b
// frames 440-879 with their stamps (and ground truth) moved 22 s earlier, so both start together, half a
// ring apart, and walk the same way round; a ends where b started, b ends where a started. Both run
// through config/pipelines/euroc_two_agents.yaml (the frontend on synth settings, a layered config), in
// lockstep; the single-agent run over all 880 frames (synth.yaml) runs beside it as the reference.
// Known answers from the exact ground truth: every frame of both agents has a pose; the maps are merged
// once, when b reaches a's ground (it comes round the ring's last corner into a's first corridor at its
// frame ~320 and stands where a started at its frame ~400; measured: at its frame 339); one map in the end;
// both trajectories in one frame: aligned to the ground truth ONCE (one SE(3) for the poses of both), the
// ATE over the 880 poses is <= 1.2x the single agent's (the issue's bar).
// The ring is point symmetric in its brick panels, floor tiles and twin checkerboards: each agent's
// mirrored corridor matches the other's with up to 78 matches (merge.min_matches 80) until the share of
// the predicted points found refuses it (docs/loop_closing.md, Merging); the merge line's share is printed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "euroc_parts.hpp"
#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 880;  // corridor_loop as the suite caches it (map_merge, multi_session tests)
constexpr int kHalf = 440;    // agent a: frames 0-439, agent b: 440-879
constexpr double kRateHz = 20.0;
constexpr std::int64_t kShiftNs = -static_cast<std::int64_t>(kHalf) * 50'000'000;  // b's stamps 22 s earlier
// b comes round the last corner into a's first corridor at about its frame 320 and is where a started at
// its frame 400 (the ring is 42 m at 1 m/s; b starts 22 m along it): a merge outside these frames is at
// another place (a look-alike) or missed the meeting.
constexpr int kMeetFirstFrame = 300;
constexpr int kMeetLastFrame = 400;
constexpr double kMaxAteRatio = 1.2;  // the issue's bar: against the single-agent run
constexpr std::chrono::seconds kRunTimeout{900};

struct Merge {
  double stamp_s = 0.0;
  int matches = 0;
  double found_percent = 0.0;
};

// The loop closer's merge lines.
std::vector<Merge> merges(const std::string& output) {
  static const std::regex line(
      R"(maps merged: map \d+ into map \d+ at keyframe \S+ \(stamp ([0-9.]+) s\): \S+ -> \S+ with (\d+) matches )"
      R"(\(\d+ of the \d+ points predicted in view found \(([0-9.]+) %)");
  std::vector<Merge> found;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    found.push_back({std::stod((*it)[1]), std::stoi((*it)[2]), std::stod((*it)[3])});
  }
  return found;
}

TEST(TwoAgentsCorridor, OppositeEndsOfTheRingMergeWhenTheyMeetWithinTheSingleAgentAte) {
  fs::path dataset;
  const std::string render_error = test::cached_synth("corridor_loop", kFrames, dataset);
  ASSERT_EQ(render_error, "");
  const test::ScratchDir dir("two_agents_corridor");
  const fs::path part_a = dir.path() / "part_a";
  const fs::path part_b = dir.path() / "part_b";
  test::make_euroc_part(dataset, part_a, 0, kHalf);
  test::make_euroc_part(dataset, part_b, kHalf, kHalf, kShiftNs);

  // The two runs one after the other (the test's one domain).
  test::ChildProcess agents(
      test::bin_dir() / "heslam-supervisor",
      {(test::source_dir() / "config/pipelines/euroc_two_agents.yaml").string(), "--domain",
       std::to_string(test::exclusive_domain_id()), "--log-dir", (dir.path() / "logs_agents").string(), "--arg",
       "dataset_a=" + part_a.string(), "--arg", "dataset_b=" + part_b.string(), "--arg",
       "frontend_config=" + (test::source_dir() / "config/frontend/synth_mapper.yaml").string(), "--arg",
       "output=" + (dir.path() / "agents.txt").string()},
      dir.path(), "supervisor_agents");
  const int agents_code = test::finish(agents, kRunTimeout);
  const std::string output = agents.out() + agents.err();
  ASSERT_EQ(agents_code, 0) << output;
  auto single = test::start_pipeline("synth", dataset, dir.path(), "single", test::exclusive_domain_id());
  ASSERT_EQ(test::finish(*single, kRunTimeout), 0) << single->err();

  const eval::Trajectory a = eval::read_trajectory(dir.path() / "agents.a.txt");
  const eval::Trajectory b = eval::read_trajectory(dir.path() / "agents.b.txt");
  EXPECT_EQ(a.size(), static_cast<std::size_t>(kHalf));
  EXPECT_EQ(b.size(), static_cast<std::size_t>(kHalf));

  // One merge, when b reaches a's ground.
  const std::vector<Merge> merged = merges(output);
  ASSERT_EQ(merged.size(), 1u) << output;
  ASSERT_FALSE(b.stamps_s.empty());
  const long merge_frame_of_b = std::lround((merged[0].stamp_s - b.stamps_s.front()) * kRateHz);
  EXPECT_GE(merge_frame_of_b, kMeetFirstFrame);
  EXPECT_LE(merge_frame_of_b, kMeetLastFrame);
  // One map in the end.
  EXPECT_FALSE(fs::exists(dir.path() / "agents.a.maps.txt"));
  EXPECT_FALSE(fs::exists(dir.path() / "agents.b.maps.txt"));
  EXPECT_EQ(output.find("refused_agent_keyframes"), std::string::npos) << output;

  // One alignment for both agents: their pairs with the ground truth together.
  const eval::AlignedPair pair_a = eval::associate(test::ground_truth_for(part_a, a), a);
  const eval::AlignedPair pair_b = eval::associate(test::ground_truth_for(part_b, b), b);
  eval::AlignedPair both = pair_a;
  for (std::size_t i = 0; i < pair_b.size(); ++i) {
    both.gt.push_back(pair_b.gt.poses_wc[i], pair_b.gt.frame_ids[i], pair_b.gt.stamps_s[i]);
    both.est.push_back(pair_b.est.poses_wc[i], pair_b.est.frame_ids[i], pair_b.est.stamps_s[i]);
  }
  EXPECT_EQ(both.size(), static_cast<std::size_t>(kFrames));
  const double ate_m = eval::compute_ape(both).translation_m.rmse;
  const double single_m = test::ate_rmse_m(dataset, dir.path() / "single.txt");
  EXPECT_EQ(eval::read_trajectory(dir.path() / "single.txt").size(), static_cast<std::size_t>(kFrames));
  std::printf(
      "[ figures  ] corridor_loop, two agents from opposite ends of the ring: merged at agent b's frame %ld with %d "
      "matches (%.1f %% of the points predicted in view found); ATE over both in one frame %.2f mm, single agent "
      "over the 880 frames %.2f mm: %.3fx (each aligned alone: a %.2f mm, b %.2f mm)\n",
      merge_frame_of_b, merged[0].matches, merged[0].found_percent, ate_m * 1e3, single_m * 1e3, ate_m / single_m,
      eval::compute_ape(pair_a).translation_m.rmse * 1e3, eval::compute_ape(pair_b).translation_m.rmse * 1e3);
  EXPECT_LE(ate_m, kMaxAteRatio * single_m);
}

}  // namespace
}  // namespace heslam
