// heslam-occupancy's maps on request during a run (docs/occupancy.md, "On request"): the synthetic room
// in lockstep (full system, no loop closer) with heslam-occupancy; held mid-run once every keyframe so far
// has its cloud, heslam-occupancy-save -f STEM gets STEM.pgm + STEM.yaml (map_server) and STEM.ply of
// those clouds, and the run goes on to its own map at the end. A request the process cannot honour (a
// folder that does not exist) is answered with why, and no process at all is one line, exit 1.
// Every wait is on a state of the run, bounded against hangs, never a timing assertion.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>

#include "components/core/occupancy/occupancy_grid.hpp"
#include "occupancy_run_watch.hpp"
#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using std::chrono::seconds;

constexpr int kRoomFrames = 150;
constexpr std::size_t kSaveAfterKeyframes = 8;  // the room makes about one keyframe every 6 frames
constexpr seconds kStateTimeout{120};           // bound of a hung run, not a performance assertion
constexpr seconds kSaveTimeout{180};

// Vertices in a PLY's header.
std::size_t ply_vertices(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  for (std::string line; std::getline(in, line) && line != "end_header";) {
    if (line.rfind("element vertex ", 0) == 0) return std::stoul(line.substr(15));
  }
  return 0;
}

int save(const fs::path& dir, const std::string& label, int domain, const std::vector<std::string>& extra,
         std::string& output) {
  std::vector<std::string> args{"--domain", std::to_string(domain)};
  args.insert(args.end(), extra.begin(), extra.end());
  test::ChildProcess tool(test::bin_dir() / "heslam-occupancy-save", args, dir, label);
  const int code = tool.wait(kSaveTimeout).value_or(-1);
  output = tool.out() + tool.err();
  return code;
}

TEST(OccupancySave, MidRunRequestWritesTheMapOfTheCloudsSoFarAndTheRunEndsWithItsOwn) {
  fs::path dataset;
  const std::string render_error = test::cached_synth("room", kRoomFrames, dataset);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("occupancy_save");
  const int domain = test::exclusive_domain_id();
  std::string output;

  // No heslam-occupancy on the domain: one line, exit 1.
  EXPECT_EQ(save(dir.path(), "nobody", domain, {"-f", (dir.path() / "none").string(), "--timeout", "2"}, output), 1);
  EXPECT_NE(output.find("heslam-occupancy-save: no heslam-occupancy on domain " + std::to_string(domain)),
            std::string::npos)
      << output;

  test::OccupancyRunWatch watch(domain, kStateTimeout);
  auto run = test::start_pipeline("synth", dataset, dir.path(), "run", domain,
                                  {"occupancy=heslam-occupancy", "loop_closer=none"});
  ASSERT_TRUE(watch.until([&] { return watch.keyframe_ids.size() >= kSaveAfterKeyframes; })) << run->err();
  const pid_t replay = test::child_pid(run->pid(), "heslam-replay");
  ASSERT_GT(replay, 0);
  ASSERT_EQ(kill(replay, SIGUSR1), 0);  // pause: the replay holds its next frame
  // Held: the last frame acknowledged and every keyframe's cloud made, so the saved map has them all.
  ASSERT_TRUE(watch.until([&] { return watch.settled(); })) << run->err();
  const std::uint64_t clouds = watch.counter("clouds");
  ASSERT_GT(clouds, 0u);

  // Relative -f: made absolute by the tool (the process may run elsewhere).
  const fs::path mid = dir.path() / "mid";
  ASSERT_EQ(save(dir.path(), "mid", domain, {"-f", mid.string()}, output), 0) << output << run->err();
  const std::regex said(R"(saved (\S+)\.pgm/\.yaml \(map_server\) and \S+\.ply: (\d+) keyframe clouds, )"
                        R"((\d+) occupied \+ (\d+) free cells, (\d+) points)");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(output, match, said)) << output;
  EXPECT_EQ(fs::path(match[1].str()), mid);
  EXPECT_EQ(std::stoull(match[2].str()), clouds);
  const OccupancyGrid grid = OccupancyGrid::read_map_server(dir.path() / "mid.yaml");
  EXPECT_EQ(grid.count(CellState::kOccupied), std::stoull(match[3].str()));
  EXPECT_EQ(grid.count(CellState::kFree), std::stoull(match[4].str()));
  EXPECT_GT(grid.count(CellState::kOccupied), 0u);
  EXPECT_EQ(ply_vertices(dir.path() / "mid.ply"), std::stoull(match[5].str()));
  EXPECT_GT(ply_vertices(dir.path() / "mid.ply"), 0u);

  // A stem it cannot write: answered with why, nothing written, exit 1; the process goes on.
  EXPECT_EQ(save(dir.path(), "bad", domain, {"-f", (dir.path() / "no_such_folder" / "x").string()}, output), 1);
  EXPECT_NE(output.find("heslam-occupancy-save: heslam-occupancy did not save: "), std::string::npos) << output;
  EXPECT_FALSE(fs::exists(dir.path() / "no_such_folder"));

  // Its status counts both (published once a second).
  EXPECT_TRUE(watch.until([&] { return watch.counter("saves") == 1 && watch.counter("saves_failed") == 1; }))
      << "saves " << watch.counter("saves") << ", failed " << watch.counter("saves_failed");

  ASSERT_EQ(kill(replay, SIGUSR2), 0);  // resume
  ASSERT_EQ(test::finish(*run), 0) << run->out() << run->err();
  // The run's own map at the end, with every keyframe of the room (more than at the request).
  const std::size_t final_points = ply_vertices(dir.path() / "run.ply");
  EXPECT_GT(final_points, ply_vertices(dir.path() / "mid.ply"));
  EXPECT_GT(OccupancyGrid::read_map_server(dir.path() / "run.yaml").count(CellState::kOccupied), 0u);
  std::printf(
      "[ figures  ] saved on request after %llu keyframe clouds (%zu points); the run's map at the end: %zu points\n",
      static_cast<unsigned long long>(clouds), ply_vertices(dir.path() / "mid.ply"), final_points);
}

}  // namespace
}  // namespace heslam
