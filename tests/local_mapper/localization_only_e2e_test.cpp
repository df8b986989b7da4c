// Localization only (synth_localize --arg mapping=off, ORB-SLAM3's localization mode) on the
// synthetic room: a map saved by a first run over the same frames is loaded, every frame is tracked
// in it, no keyframe is created, and the saved map file is left as it was. Real processes under
// heslam-supervisor on this test's own domain.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "components/core/mapping/map_file.hpp"
#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 40;

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// The frontend's summary line "processed N frames (...), K keyframes": K, or -1 without one.
int frontend_keyframes(const std::string& output) {
  static const std::regex summary(R"(processed (\d+) frames \([^)]*\), (\d+) keyframes)");
  std::smatch match;
  return std::regex_search(output, match, summary) ? std::stoi(match[2]) : -1;
}

TEST(LocalizationOnly, TracksEveryFrameInTheSavedMapAndCreatesNoKeyframe) {
  fs::path dataset;
  ASSERT_EQ(test::cached_synth("room", kFrames, dataset), "");
  const test::ScratchDir dir("localization_only");
  const int domain = test::exclusive_domain_id();

  const fs::path saved = dir.path() / "maps/room.map";
  auto first = test::start_pipeline("synth", dataset, dir.path(), "first", domain,
                                    {"loop_closer=none", "save_map=" + saved.string()});
  ASSERT_EQ(test::finish(*first), 0) << first->out() << first->err();
  const std::string saved_bytes = read_bytes(saved);
  ASSERT_FALSE(saved_bytes.empty());
  const std::size_t saved_keyframes = load_map_file(saved).map.keyframes.size();
  ASSERT_GT(saved_keyframes, 1u);

  auto second = test::start_pipeline("synth_localize", dataset, dir.path(), "second", domain,
                                     {"map=" + saved.string(), "mapping=off"});
  ASSERT_EQ(test::finish(*second), 0) << second->out() << second->err();
  const std::string output = second->out() + second->err();
  EXPECT_NE(output.find("localization only: mapping off"), std::string::npos) << output;
  EXPECT_NE(output.find("relocalized in the saved map at frame 0\n"), std::string::npos) << output;

  // Every frame has a pose, none is untracked.
  EXPECT_EQ(eval::read_trajectory(dir.path() / "second.txt").size(), static_cast<std::size_t>(kFrames)) << output;
  EXPECT_EQ(test::lost_entries(dir.path() / "second.lost.txt"), 0) << output;
  // No keyframe created: the frontend made none, the mapper's working copy holds the saved map's.
  EXPECT_EQ(frontend_keyframes(output), 0) << output;
  EXPECT_EQ(load_map_file(dir.path() / "second.map").map.keyframes.size(), saved_keyframes) << output;
  // The user's map file is untouched.
  EXPECT_EQ(read_bytes(saved), saved_bytes);
}

}  // namespace
}  // namespace heslam
