// Recovery from faults in combination: the full system (config/pipelines/euroc.yaml:
// replay, frontend, local mapper, loop closer, recorder under heslam-supervisor, lockstep) on EuRoC
// MH01 with components killed with SIGKILL mid-run, alone, two within half a second of each other
// (a power glitch, an OOM kill), or all but the supervisor; every run must end with every frame
// tracked and the trajectory as good as an undisturbed run's. Kills are triggered by the run's
// progress (frames recorded), not by wall time, so a seed replays the same faults on any machine.
//
// The soak test's size comes from the environment (tools/soak.sh sets it): HESLAM_SOAK_RUNS (default
// 2), HESLAM_SOAK_SEED (default 1; each run r uses seed + r), HESLAM_SOAK_KILLS (events per run,
// default 3). Each test uses its own DDS domain; the supervisor's children die with it.
#include <gtest/gtest.h>

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fault_plan.hpp"
#include "journal_frames.hpp"
#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kClipFrames = 160;  // euroc_mh01_handheld
// The issue's bound: a run with faults is within this factor of the undisturbed run's ATE.
constexpr double kAteFactor = 1.2;
// How long to look for a component that is not running at its kill time (restarting after an
// earlier kill) before going on without killing it.
constexpr std::chrono::milliseconds kFindProcessWait{3000};
constexpr std::chrono::milliseconds kPoll{10};

struct RunResult {
  int exit_code = -1;
  std::string output;              // the supervisor's
  std::size_t poses = 0;           // lines of the trajectory
  double ate_m = -1.0;             // against the ground truth (SE(3) aligned, as heslam-eval ape)
  std::vector<std::string> kills;  // what was killed, for the failure message and the figures
  std::size_t processes_killed = 0;
  int keyframes_without_stamp = -1;  // in the keyframe trajectory (a keyframe whose creation was never seen)
};

// How far the run is: the frames the frontend has finished or the recorder has recorded, whichever
// is more. The recorder can lag by up to a DDS lease (2 s) after a frontend kill: the restarted
// frontend's odometry is held until the killed writer's lease expires (runtime/checked_reader.hpp),
// so timing kills by the recorder alone could fire them after the replay ended, in the stop phase.
std::size_t frames_done(const fs::path& dir, const std::string& label) {
  return std::max(test::frames_in_journal(dir / (label + ".journal")),
                  test::frames_in_journal(dir / (label + ".frontend")));
}

pid_t find_component(pid_t supervisor, const std::string& component) {
  const auto deadline = std::chrono::steady_clock::now() + kFindProcessWait;
  for (;;) {
    const pid_t pid = test::child_pid(supervisor, test::component_comm(component));
    if (pid > 0 || std::chrono::steady_clock::now() >= deadline) return pid;
    std::this_thread::sleep_for(kPoll);
  }
}

// Runs euroc.yaml on `dataset` into dir/label.txt and executes `plan` against it.
RunResult run_with_faults(const fs::path& dataset, const fs::path& dir, const std::string& label,
                          const std::vector<test::KillEvent>& plan) {
  auto supervisor = test::start_pipeline("euroc", dataset, dir, label, test::exclusive_domain_id());
  const auto deadline = std::chrono::steady_clock::now() + test::kPipelineTimeout;
  RunResult result;
  std::size_t next = 0;
  while (next < plan.size() && std::chrono::steady_clock::now() < deadline &&
         !supervisor->wait(std::chrono::milliseconds(0))) {
    const test::KillEvent& event = plan[next];
    if (frames_done(dir, label) < static_cast<std::size_t>(event.at_frame)) {
      std::this_thread::sleep_for(kPoll);
      continue;
    }
    std::string done = "frame " + std::to_string(frames_done(dir, label)) + ":";
    for (std::size_t i = 0; i < event.components.size(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(event.gaps_ms[i]));
      const pid_t pid = find_component(supervisor->pid(), event.components[i]);
      const bool killed = pid > 0 && ::kill(pid, SIGKILL) == 0;
      result.processes_killed += killed ? 1 : 0;
      done += " " + event.components[i] + (killed ? "" : " (not running)");
    }
    result.kills.push_back(done);
    ++next;
  }
  result.exit_code = test::finish(*supervisor);
  result.output = supervisor->out() + supervisor->err();
  const fs::path trajectory = dir / (label + ".txt");
  if (fs::exists(trajectory)) {
    result.poses = eval::read_trajectory(trajectory).size();
    if (result.poses > 0) result.ate_m = test::ate_rmse_m(dataset, trajectory);
  }
  const fs::path keyframes = dir / (label + ".keyframes.txt");
  if (fs::exists(keyframes)) {
    const eval::Trajectory keyframe_trajectory = eval::read_trajectory(keyframes);
    result.keyframes_without_stamp =
        static_cast<int>(std::count(keyframe_trajectory.stamps_s.begin(), keyframe_trajectory.stamps_s.end(), 0.0));
  }
  return result;
}

// The same pipeline without faults: the reference of the ATE bound (lockstep runs are repeatable).
double undisturbed_ate_m(const fs::path& dataset, const fs::path& dir) {
  const RunResult run = run_with_faults(dataset, dir, "undisturbed", {});
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(run.poses, kClipFrames) << run.output;
  return run.ate_m;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += "\n  " + line;
  return text;
}

void expect_recovered(const RunResult& run, double undisturbed_m, const std::string& what) {
  EXPECT_EQ(run.exit_code, 0) << what << joined(run.kills) << "\n" << run.output;
  EXPECT_EQ(run.poses, kClipFrames) << what << joined(run.kills) << "\n" << run.output;
  EXPECT_GT(run.ate_m, 0.0) << what;
  EXPECT_EQ(run.keyframes_without_stamp, 0) << what << joined(run.kills);
  EXPECT_LT(run.ate_m, undisturbed_m * kAteFactor) << what << joined(run.kills) << "\n" << run.output;
}

std::uint64_t env_or(const char* name, std::uint64_t fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? std::strtoull(value, nullptr, 10) : fallback;
}

// A frontend killed close to the end of the run: its successor publishes while the killed writer
// still counts as matched (its 2 s DDS lease), so the recorder holds those samples back and the
// lockstep run ends inside that window (seen in the soak, seed 2). The recorder gets them when the
// lease expires; at its shutdown it waits for that take-over (tools/recorder), so the outcome does
// not depend on how long the other components take to stop before it.
TEST(Recovery, FrontendKilledNearTheEndLosesNoFrame) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("recovery_near_end");
  constexpr int kAtFrame = 150;  // 10 frames before the end: the run ends well within the lease
  const RunResult run = run_with_faults(dataset, dir.path(), "near_end", {{kAtFrame, {"frontend"}, {0}}});
  EXPECT_EQ(run.exit_code, 0) << joined(run.kills) << "\n" << run.output;
  EXPECT_EQ(run.poses, kClipFrames) << joined(run.kills) << "\n" << run.output;
  std::printf("[ figures  ] MH01 full system, frontend killed at frame %d: rc %d, %zu/%zu poses, ATE %.3f mm\n",
              kAtFrame, run.exit_code, run.poses, kClipFrames, run.ate_m * 1e3);
}

// The mapper and the frontend killed within half a second of each other, in either order.
// Before the fix: mapper, then frontend 50 ms later: the restarted frontend waited for map states the
// restarted mapper published only after a keyframe, started a new map, and the mapper dropped its own
// map file as "from another run" (rc 0, 160 poses, ATE 142 mm); frontend, then mapper 300 ms later:
// the frontend relocalized, which failed on frames 61 and 62 (158/160 poses).
TEST(Recovery, MapperAndFrontendKilledTogetherKeepTheMapAndLoseNoFrame) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("recovery_pair");
  const double undisturbed_m = undisturbed_ate_m(dataset, dir.path());
  constexpr int kAtFrame = 60;
  constexpr int kMapperFirstGapMs = 50;
  constexpr int kFrontendFirstGapMs = 300;
  const RunResult mapper_first = run_with_faults(dataset, dir.path(), "mapper_first",
                                                 {{kAtFrame, {"local_mapper", "frontend"}, {0, kMapperFirstGapMs}}});
  expect_recovered(mapper_first, undisturbed_m, "mapper, then frontend");
  const RunResult frontend_first = run_with_faults(
      dataset, dir.path(), "frontend_first", {{kAtFrame, {"frontend", "local_mapper"}, {0, kFrontendFirstGapMs}}});
  expect_recovered(frontend_first, undisturbed_m, "frontend, then mapper");
  EXPECT_EQ(mapper_first.output.find("from another run"), std::string::npos);
  EXPECT_NE(frontend_first.output.find("resuming in the local mapper's map"), std::string::npos)
      << frontend_first.output;
  std::printf(
      "[ figures  ] MH01 full system, mapper and frontend killed at frame %d: mapper, frontend %d ms later: "
      "%zu/%zu poses, ATE %.3f mm; frontend, mapper %d ms later: %zu/%zu poses, ATE %.3f mm; undisturbed "
      "%.3f mm\n",
      kAtFrame, kMapperFirstGapMs, mapper_first.poses, kClipFrames, mapper_first.ate_m * 1e3, kFrontendFirstGapMs,
      frontend_first.poses, kClipFrames, frontend_first.ate_m * 1e3, undisturbed_m * 1e3);
}

// The frontend killed while the mapper's map file is unusable (corrupted on disk;
// the same holds for a frontend on another host than the mapper, which has no file at all). Before:
// the restarted frontend started a new map, reused keyframe id fe:1, the mapper refused it ("id
// already in the map") and the run lost 59-88 frames with poses 255-400 mm off, rc 0. Now it takes
// the mapper's live map from DDS (map/mapper_keyframes + the state topics) and tracks on in it, and
// its ids start in a range of their own. The file is kept corrupt for the whole restart window (the
// mapper may save once more while it maps the last keyframe).
TEST(Recovery, FrontendRestartedWithAnUnusableMapFileResumesInTheMappersMapFromDds) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("recovery_corrupt_map");
  const double undisturbed_m = undisturbed_ate_m(dataset, dir.path());
  const std::string label = "corrupt_map";
  auto supervisor = test::start_pipeline("euroc", dataset, dir.path(), label, test::exclusive_domain_id());
  constexpr std::size_t kAtFrame = 60;
  constexpr std::chrono::milliseconds kKeepCorrupt{4000};
  const fs::path map_file = dir.path() / (label + ".map");
  const auto deadline = std::chrono::steady_clock::now() + test::kPipelineTimeout;
  bool killed = false;
  while (!killed && std::chrono::steady_clock::now() < deadline && !supervisor->wait(std::chrono::milliseconds(0))) {
    if (frames_done(dir.path(), label) < kAtFrame) {
      std::this_thread::sleep_for(kPoll);
      continue;
    }
    const pid_t pid = find_component(supervisor->pid(), "frontend");
    killed = pid > 0 && ::kill(pid, SIGKILL) == 0;
  }
  ASSERT_TRUE(killed) << supervisor->out() << supervisor->err();
  const std::string garbage = "this is not a heslam map file\n";
  const auto keep_until = std::chrono::steady_clock::now() + kKeepCorrupt;
  while (std::chrono::steady_clock::now() < keep_until) {
    std::ifstream in(map_file);
    std::string first;
    std::getline(in, first);
    if (first + "\n" != garbage) std::ofstream(map_file, std::ios::trunc) << garbage;
    std::this_thread::sleep_for(kPoll);
  }
  const int exit_code = test::finish(*supervisor);
  const std::string output = supervisor->out() + supervisor->err();
  const fs::path trajectory = dir.path() / (label + ".txt");
  ASSERT_TRUE(fs::exists(trajectory)) << output;
  const std::size_t poses = eval::read_trajectory(trajectory).size();
  const double ate_m = test::ate_rmse_m(dataset, trajectory);
  std::printf(
      "[ figures  ] MH01 full system, frontend killed at frame %zu with the map file corrupt: rc %d, %zu/%zu "
      "poses, ATE %.3f mm (undisturbed %.3f mm)\n",
      kAtFrame, exit_code, poses, kClipFrames, ate_m * 1e3, undisturbed_m * 1e3);
  EXPECT_EQ(exit_code, 0) << output;
  EXPECT_EQ(poses, kClipFrames) << output;
  EXPECT_NE(output.find("of the local mapper's map from DDS"), std::string::npos) << output;
  EXPECT_NE(output.find("resuming in the local mapper's map"), std::string::npos) << output;
  EXPECT_EQ(output.find("id already in the map"), std::string::npos) << output;
  EXPECT_EQ(output.find("; starting a new map"), std::string::npos) << output;
  EXPECT_LT(ate_m, undisturbed_m * kAteFactor) << output;
}

// The mapper's restart window (docs/local_mapper.md, The restart window): killed after a keyframe's map save
// and before the states of that step were all published. Made exact here by the mapper's test aid
// (test.kill_after_saved_keyframes: SIGKILL right after the save of its Nth keyframe, first start only). Before
// the fix the disposals of the points that step removed never left, and the loop closer's copy of the map kept
// them for good (the street: 24,954 points against the mapper's 24,652). Known answers: the restarted mapper
// disposes again exactly the points the saved step removed, and at the end the loop closer's copy holds the
// mapper's points, id for id (count and digest of the ids, both shutdown lines), with every frame tracked.
TEST(Recovery, MapperKilledBetweenSaveAndPublishLeavesTheLoopClosersCopyExact) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("recovery_save_window");
  constexpr int kKillAfterKeyframes = 8;  // MH01 maps 19 keyframes; the 8th step culls recent points
  const fs::path mapper_config = dir.path() / "kill_after_save.yaml";
  std::ofstream(mapper_config) << "%YAML:1.0\n---\ntest:\n  kill_after_saved_keyframes: " << kKillAfterKeyframes
                               << "\n";
  const std::string label = "save_window";
  auto supervisor = test::start_pipeline("euroc", dataset, dir.path(), label, test::exclusive_domain_id(),
                                         {"mapper_config=" + mapper_config.string()});
  const int exit_code = test::finish(*supervisor);
  const std::string output = supervisor->out() + supervisor->err();
  ASSERT_EQ(exit_code, 0) << output;
  const fs::path trajectory = dir.path() / (label + ".txt");
  EXPECT_EQ(eval::read_trajectory(trajectory).size(), kClipFrames) << output;

  std::smatch killed;
  ASSERT_TRUE(std::regex_search(output, killed,
                                std::regex(R"(SIGKILL after the save of keyframe \S+, before its \d+ keyframe states, )"
                                           R"(\d+ point states and (\d+) disposals are published)")))
      << output;
  const int removed = std::stoi(killed[1]);
  EXPECT_GT(removed, 0) << "the step before the kill removed no point: the window is not tested";
  std::smatch again;
  ASSERT_TRUE(
      std::regex_search(output, again, std::regex(R"(disposed again (\d+) points the last saved step removed)")))
      << output;
  EXPECT_EQ(std::stoi(again[1]), removed);

  std::smatch mapper_map;
  std::smatch copy;
  ASSERT_TRUE(std::regex_search(
      output, mapper_map, std::regex(R"(map: (\d+) keyframes, (\d+) points, version \d+, point ids ([0-9a-f]+))")))
      << output;
  ASSERT_TRUE(std::regex_search(
      output, copy,
      std::regex(R"(map copy: (\d+) keyframes, (\d+) points \(map version \d+, point ids ([0-9a-f]+)\))")))
      << output;
  EXPECT_EQ(copy[1].str(), mapper_map[1].str()) << "keyframes";
  EXPECT_EQ(copy[2].str(), mapper_map[2].str()) << "points";
  EXPECT_EQ(copy[3].str(), mapper_map[3].str()) << "point ids";
  std::printf(
      "[ figures  ] MH01 full system, mapper killed after the save of its keyframe %d (%d points removed, not yet "
      "disposed): disposed again %s; the loop closer's copy %s points, the mapper's map %s (digests %s / %s); ATE "
      "%.3f mm\n",
      kKillAfterKeyframes, removed, again[1].str().c_str(), copy[2].str().c_str(), mapper_map[2].str().c_str(),
      copy[3].str().c_str(), mapper_map[3].str().c_str(), test::ate_rmse_m(dataset, trajectory) * 1e3);
}

// Fault-injection soak: HESLAM_SOAK_RUNS lockstep runs, each with HESLAM_SOAK_KILLS seeded kill
// events of random components (single, near-simultaneous pairs, all but the supervisor). Replay a
// failure with tools/soak.sh --seed S --runs 1 (S as printed).
TEST(Recovery, SoakRandomKillsLoseNoFrameAndKeepTheAccuracy) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("recovery_soak");
  const std::uint64_t runs = env_or("HESLAM_SOAK_RUNS", 2);
  const std::uint64_t seed = env_or("HESLAM_SOAK_SEED", 1);
  test::FaultPlanOptions options;
  options.kills = static_cast<int>(env_or("HESLAM_SOAK_KILLS", static_cast<std::uint64_t>(options.kills)));
  const double undisturbed_m = undisturbed_ate_m(dataset, dir.path());
  double worst_m = 0.0;
  double best_m = 1e9;
  std::size_t processes_killed = 0;
  int failed = 0;
  for (std::uint64_t r = 0; r < runs; ++r) {
    const std::uint64_t run_seed = seed + r;
    const std::vector<test::KillEvent> plan = test::plan_faults(run_seed, options);
    std::string planned;
    for (const test::KillEvent& event : plan) planned += "; " + event.describe();
    std::printf("[ soak     ] run %llu seed %llu: %s\n", static_cast<unsigned long long>(r + 1),
                static_cast<unsigned long long>(run_seed), planned.substr(2).c_str());
    std::fflush(stdout);
    const std::string label = "soak_" + std::to_string(run_seed);
    const RunResult run = run_with_faults(dataset, dir.path(), label, plan);
    processes_killed += run.processes_killed;
    const bool ok = run.exit_code == 0 && run.poses == kClipFrames && run.ate_m > 0.0 &&
                    run.ate_m < undisturbed_m * kAteFactor && run.keyframes_without_stamp == 0;
    failed += ok ? 0 : 1;
    worst_m = std::max(worst_m, run.ate_m);
    best_m = std::min(best_m, run.ate_m);
    std::printf("[ soak     ] run %llu seed %llu: %s: rc %d, %zu/%zu poses, ATE %.3f mm; killed%s\n",
                static_cast<unsigned long long>(r + 1), static_cast<unsigned long long>(run_seed), ok ? "ok" : "FAILED",
                run.exit_code, run.poses, kClipFrames, run.ate_m * 1e3, joined(run.kills).c_str());
    std::fflush(stdout);
    expect_recovered(
        run, undisturbed_m,
        "seed " + std::to_string(run_seed) + " (tools/soak.sh --seed " + std::to_string(run_seed) + " --runs 1)");
    if (!ok) {
      std::printf("[ soak     ] logs of seed %llu kept in %s\n", static_cast<unsigned long long>(run_seed),
                  (dir.path() / ("logs_" + label)).c_str());
    }
  }
  std::printf(
      "[ figures  ] soak: %llu runs from seed %llu, %d kill events per run, %zu processes killed, %d failed; "
      "ATE %.3f-%.3f mm (undisturbed %.3f mm, bound %.3f mm)\n",
      static_cast<unsigned long long>(runs), static_cast<unsigned long long>(seed), options.kills, processes_killed,
      failed, best_m * 1e3, worst_m * 1e3, undisturbed_m * 1e3, undisturbed_m * kAteFactor * 1e3);
}

}  // namespace
}  // namespace heslam
