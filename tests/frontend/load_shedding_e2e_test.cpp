// Load shedding end to end (issue 41): the real-time pipeline (config/pipelines/euroc_realtime.yaml) on
// MH01 with a frontend made slower than the camera on purpose (debug.frame_delay_ms above the 50 ms
// frame period), so that it is behind at any machine speed. What must hold whatever the timing: every
// published frame is tracked, untracked (listed as lost) or counted as missed; the frames shed are
// counted, among the missed, and said in the frontend's summary; the poses it has are of this clip.
// No timing is asserted.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kClipFrames = 160;

int count_in(const std::string& output, const char* pattern) {
  const std::regex line(pattern);
  std::smatch match;
  return std::regex_search(output, match, line) ? std::stoi(match[1]) : 0;
}

std::size_t lines_without_hash(const fs::path& file) {
  std::ifstream in(file);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) lines += !line.empty() && line[0] != '#' ? 1 : 0;
  return lines;
}

TEST(LoadSheddingEndToEnd, RealTimeBehindTheCameraShedsStaleFramesAndCountsThem) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("shedding");
  // Shedding as shipped in euroc_mapper_realtime.yaml, written out so the test does not depend on it.
  const fs::path overlay = dir.path() / "slow_frontend.yaml";
  std::ofstream(overlay) << "%YAML:1.0\n---\nrealtime:\n  shed_frames_after_ms: 100\n  predict_over_gaps: true\n"
                            "debug:\n  frame_delay_ms: 150\n";
  auto run = test::start_pipeline("euroc_realtime", dataset, dir.path(), "slow", test::exclusive_domain_id(),
                                  {"frontend_config=" + overlay.string(), "loop_closer=none"});
  ASSERT_EQ(test::finish(*run), 0) << run->out() << run->err();
  const std::string output = run->out() + run->err();
  const int processed = count_in(output, R"(processed (\d+) frames)");
  const int missed = count_in(output, R"((\d+) frames missed)");
  const int shed = count_in(output, R"((\d+) frames shed)");
  const eval::Trajectory estimate = eval::read_trajectory(dir.path() / "slow.txt");
  const std::size_t untracked = lines_without_hash(dir.path() / "slow.lost.txt");
  std::printf(
      "[ figures  ] MH01 real time, frontend delayed 150 ms a frame: %d processed, %d missed (%d shed), "
      "%zu poses, ATE rmse %.2f mm\n",
      processed, missed, shed, estimate.size(), test::ate_rmse_m(dataset, dir.path() / "slow.txt") * 1e3);
  EXPECT_EQ(processed + missed, kClipFrames) << output;  // every published frame processed or missed
  EXPECT_EQ(estimate.size() + untracked, static_cast<std::size_t>(processed)) << output;
  // 150 ms a frame against a 50 ms period: behind whatever the machine, so stale frames wait.
  EXPECT_GT(shed, 0) << output;
  EXPECT_LE(shed, missed) << output;  // shed frames have no pose: they are among the missed
  EXPECT_GT(estimate.size(), 0u) << output;
  EXPECT_LT(test::ate_rmse_m(dataset, dir.path() / "slow.txt"), 0.5) << output;  // inside the clip's box
  std::ostringstream tracked;
  tracked << "pipeline finished: tracked " << estimate.size() << "/" << kClipFrames << " frames";
  EXPECT_NE(output.find(tracked.str()), std::string::npos) << output;
}

// Without shedding the same slow frontend tracks frames in order however late they are (the image
// reader's keep-last queue drops the oldest): nothing shed, every frame still accounted for.
TEST(LoadSheddingEndToEnd, RealTimeWithoutSheddingCountsEveryFrameToo) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("no_shedding");
  const fs::path overlay = dir.path() / "slow_frontend.yaml";
  std::ofstream(overlay) << "%YAML:1.0\n---\nrealtime:\n  shed_frames_after_ms: 0\n  predict_over_gaps: false\n"
                            "debug:\n  frame_delay_ms: 150\n";
  auto run = test::start_pipeline("euroc_realtime", dataset, dir.path(), "slow", test::exclusive_domain_id(),
                                  {"frontend_config=" + overlay.string(), "loop_closer=none"});
  ASSERT_EQ(test::finish(*run), 0) << run->out() << run->err();
  const std::string output = run->out() + run->err();
  const int processed = count_in(output, R"(processed (\d+) frames)");
  const int missed = count_in(output, R"((\d+) frames missed)");
  EXPECT_EQ(processed + missed, kClipFrames) << output;
  EXPECT_GT(missed, 0) << output;  // 150 ms a frame cannot take 20 frames a second
  EXPECT_EQ(output.find("frames shed"), std::string::npos) << output;
  const eval::Trajectory estimate = eval::read_trajectory(dir.path() / "slow.txt");
  EXPECT_EQ(estimate.size() + lines_without_hash(dir.path() / "slow.lost.txt"), static_cast<std::size_t>(processed));
}

}  // namespace
}  // namespace heslam
