// The atlas end to end: config/pipelines/synth.yaml (replay, frontend, local mapper, loop closer,
// recorder under heslam-supervisor, lockstep) on heslam-synth's corridor_jump, whose camera is
// carried 9 m along its path between frames 119 and 120, round a corner to corridor it has never seen.
// With the shipped atlas.new_map_after_s (1 s of frame stamps) the frontend starts map 1 at most 3
// frames after the rule allows it (the first lost frame + 20), every later frame has a pose, the
// trajectory's side file (STEM.maps.txt) says which map each pose is in, and the mapper's map holds
// two maps that no observation, spanning-tree edge or covisibility edge joins, each with its own root.
// Then the same run with the local mapper and the frontend killed with SIGKILL while map 1 is being
// built: nothing is lost, every pose is in the same map as in the undisturbed run.
#include <gtest/gtest.h>

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "components/core/mapping/map_file.hpp"
#include "fault_plan.hpp"
#include "journal_frames.hpp"
#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 240;
constexpr int kJump = 120;       // corridor_jump: trajectory.teleport_at_s 6.0 at 20 Hz
constexpr int kRuleFrames = 20;  // the shipped atlas.new_map_after_s, 1.0 s at 20 Hz
constexpr int kMaxFramesAfterRule = 3;
constexpr std::chrono::milliseconds kPoll{10};

struct AtlasRun {
  int exit_code = -1;
  std::string output;                   // the supervisor's
  std::map<std::uint64_t, MapId> maps;  // seq -> map of every pose (STEM.maps.txt)
  std::vector<std::uint64_t> lost;      // seqs of STEM.lost.txt
  std::size_t poses = 0;
  std::vector<std::string> kills;
};

// STEM.maps.txt: "seq stamp_s map_id" per pose; comment and keyframe lines skipped.
std::map<std::uint64_t, MapId> read_maps(const fs::path& path) {
  std::map<std::uint64_t, MapId> maps;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("keyframe", 0) == 0) continue;
    std::istringstream fields(line);
    std::uint64_t seq = 0;
    double stamp_s = 0.0;
    MapId map_id = 0;
    if (fields >> seq >> stamp_s >> map_id) maps[seq] = map_id;
  }
  return maps;
}

std::vector<std::uint64_t> read_lost(const fs::path& path) {
  std::vector<std::uint64_t> lost;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::uint64_t seq = 0;
    if (!line.empty() && line[0] != '#' && std::istringstream(line) >> seq) lost.push_back(seq);
  }
  return lost;
}

// Runs synth.yaml on `dataset` into dir/label.txt, killing `plan`'s components at its frames.
AtlasRun run_atlas(const fs::path& dataset, const fs::path& dir, const std::string& label,
                   const std::vector<test::KillEvent>& plan) {
  auto supervisor = test::start_pipeline("synth", dataset, dir, label, test::exclusive_domain_id());
  const auto deadline = std::chrono::steady_clock::now() + test::kPipelineTimeout;
  AtlasRun run;
  std::size_t next = 0;
  while (next < plan.size() && std::chrono::steady_clock::now() < deadline &&
         !supervisor->wait(std::chrono::milliseconds(0))) {
    if (test::frames_in_journal(dir / (label + ".frontend")) < static_cast<std::size_t>(plan[next].at_frame)) {
      std::this_thread::sleep_for(kPoll);
      continue;
    }
    for (const std::string& component : plan[next].components) {
      const pid_t pid = test::child_pid(supervisor->pid(), test::component_comm(component));
      const bool killed = pid > 0 && ::kill(pid, SIGKILL) == 0;
      run.kills.push_back("frame " + std::to_string(plan[next].at_frame) + ": " + component +
                          (killed ? "" : " (not running)"));
    }
    ++next;
  }
  run.exit_code = test::finish(*supervisor);
  run.output = supervisor->out() + supervisor->err();
  run.maps = read_maps(dir / (label + ".maps.txt"));
  run.lost = read_lost(dir / (label + ".lost.txt"));
  if (fs::exists(dir / (label + ".txt"))) run.poses = eval::read_trajectory(dir / (label + ".txt")).size();
  return run;
}

// The mapper's map (STEM.map) is a partition by map id: no observation, spanning-tree or covisibility
// edge crosses two maps, and each map has exactly one root. Returns the keyframes of each map.
std::map<MapId, int> expect_partition(const fs::path& map_file) {
  std::map<MapId, int> keyframes;
  const MapSnapshot snapshot = load_map_file(map_file);
  const Map& map = snapshot.map;
  std::map<MapId, int> roots;
  for (const auto& [id, keyframe] : map.keyframes) {
    ++keyframes[keyframe.map_id];
    if (keyframe.parent == kNoId) {
      ++roots[keyframe.map_id];
    } else if (const Keyframe* parent = map.keyframe(keyframe.parent)) {
      EXPECT_EQ(parent->map_id, keyframe.map_id) << "keyframe " << format_id(id) << "'s parent";
    }
    for (const auto& [neighbour, weight] : keyframe.covisible) {
      if (const Keyframe* other = map.keyframe(neighbour)) {
        EXPECT_EQ(other->map_id, keyframe.map_id) << "keyframe " << format_id(id) << " covisible";
      }
    }
  }
  for (const auto& [id, point] : map.points) {
    for (const auto& [keyframe_id, index] : point.observations) {
      EXPECT_EQ(map.keyframe(keyframe_id)->map_id, point.map_id) << "point " << format_id(id);
    }
  }
  for (const auto& [map_id, count] : keyframes) EXPECT_EQ(roots[map_id], 1) << "roots of map " << map_id;
  return keyframes;
}

TEST(AtlasE2E, TeleportedCameraGoesOnInANewMapAndSurvivesKills) {
  fs::path dataset;
  const std::string render_error = test::cached_synth("corridor_jump", kFrames, dataset);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("atlas_e2e");

  const AtlasRun run = run_atlas(dataset, dir.path(), "atlas", {});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  ASSERT_FALSE(run.lost.empty()) << "the teleport was tracked: no frame lost";
  const std::uint64_t lost_at = run.lost.front();
  EXPECT_GE(lost_at, static_cast<std::uint64_t>(kJump));
  EXPECT_LE(lost_at, static_cast<std::uint64_t>(kJump + 1));
  const std::uint64_t started_at = run.lost.back() + 1;
  // The lost frames are one run, ended by the new map within 3 frames of the rule allowing it.
  EXPECT_EQ(run.lost.size(), started_at - lost_at);
  EXPECT_GE(started_at, lost_at + kRuleFrames);
  EXPECT_LE(started_at, lost_at + kRuleFrames + kMaxFramesAfterRule);
  EXPECT_EQ(run.poses + run.lost.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(run.maps.size(), run.poses) << "STEM.maps.txt has a line per pose";
  for (const auto& [seq, map_id] : run.maps) {
    EXPECT_EQ(map_id, seq < lost_at ? kFirstMapId : 1u) << "frame " << seq;
    if (seq >= lost_at) {
      EXPECT_GE(seq, started_at);
    }
  }
  EXPECT_NE(run.output.find("new map 1 at frame " + std::to_string(started_at)), std::string::npos) << run.output;
  const std::map<MapId, int> keyframes = expect_partition(dir.path() / "atlas.map");
  ASSERT_EQ(keyframes.size(), 2u);

  // Killed while map 1 grows: the mapper, then the frontend; lockstep, so nothing may differ.
  const std::vector<test::KillEvent> plan{{static_cast<int>(started_at) + 20, {"local_mapper"}, {0}},
                                          {static_cast<int>(started_at) + 50, {"frontend"}, {0}}};
  const AtlasRun killed = run_atlas(dataset, dir.path(), "killed", plan);
  std::string kills;
  for (const std::string& kill : killed.kills) kills += "\n  " + kill;
  ASSERT_EQ(killed.exit_code, 0) << kills << "\n" << killed.output;
  // The kills happened (a run that ended before them would prove nothing).
  ASSERT_EQ(killed.kills.size(), plan.size()) << kills;
  EXPECT_EQ(kills.find("not running"), std::string::npos) << kills;
  EXPECT_EQ(killed.lost, run.lost) << kills;
  EXPECT_EQ(killed.maps, run.maps) << kills;
  EXPECT_EQ(expect_partition(dir.path() / "killed.map").size(), 2u);
  std::printf(
      "[ figures  ] corridor_jump %d frames: lost at frame %lu, new map 1 at frame %lu (rule: frame %lu), "
      "%d + %d keyframes; with the mapper and the frontend killed:%s\n",
      kFrames, static_cast<unsigned long>(lost_at), static_cast<unsigned long>(started_at),
      static_cast<unsigned long>(lost_at + kRuleFrames), keyframes.at(0), keyframes.at(1), kills.c_str());
}

}  // namespace
}  // namespace heslam
