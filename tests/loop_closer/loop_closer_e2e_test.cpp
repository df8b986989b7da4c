// The loop closer end to end: replay -> frontend -> local mapper -> loop closer -> recorder as real
// processes under heslam-supervisor, in lockstep (config/pipelines/synth.yaml and
// euroc.yaml with --arg loop_closer=...). Known answers from heslam-synth's exact ground
// truth: the synthetic corridor loop is closed where the camera comes back and the drift goes; the
// room (which revisits all the time) gets no false loop; a killed loop closer is restarted and the
// loop is still closed. Each test uses its own DDS domain; children are always killed and reaped.
#include <gtest/gtest.h>

#include <signal.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// corridor_loop walks once round the 42 m ring and past its start (docs/tools/synth.md): by this
// frame the camera is back where it started and has seen the first corridor again for ~3 s.
constexpr int kCorridorFrames = 960;
// The issue's bar for a closed loop: ATE after closing at most 0.2 % of the path length.
constexpr double kMaxAteOfPath = 0.002;
constexpr const char* kLoopCloserComm = "heslam-loop-clo";
// ATE of the same lockstep run without a loop closer (--arg loop_closer=none): closing the loop
// must at least halve it. The odometry drift test (tests/local_mapper/odometry_drift_e2e_test.cpp)
// re-measures it on every run of the suite and holds it at or below this figure.
constexpr double kCorridorOdometryAteM = 0.042967;

int test_domain() { return test::exclusive_domain_id(); }

// "processed N keyframes: C loop candidates, A loops accepted, R rejected, ..." from the loop closer.
int loops_accepted(const std::string& output) {
  static const std::regex summary(R"((\d+) loops accepted)");
  std::smatch match;
  int total = 0;
  std::string::const_iterator from = output.begin();
  while (std::regex_search(from, output.end(), match, summary)) {
    total += std::stoi(match[1]);
    from = match.suffix().first;
  }
  return total;
}

// One rendered corridor loop for every test process of the build (rendering takes ~30 s).
class CorridorLoop : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string render_error = test::cached_synth("corridor_loop", kCorridorFrames, dataset_);
    ASSERT_TRUE(render_error.empty()) << render_error;
  }
  fs::path dataset_;
  const test::ScratchDir dir_{"corridor"};
};

struct RunResult {
  int code = -1;
  std::string output;
  double ate_m = 0.0;
  std::size_t poses = 0;
};

RunResult run(const std::string& pipeline, const fs::path& dataset, const fs::path& dir, const std::string& label,
              const std::string& loop_closer) {
  auto supervisor = test::start_pipeline(pipeline, dataset, dir, label, test_domain(), {"loop_closer=" + loop_closer});
  RunResult result;
  result.code = test::finish(*supervisor);
  result.output = supervisor->out() + supervisor->err();
  if (result.code == 0) {
    result.poses = eval::read_trajectory(dir / (label + ".txt")).size();
    result.ate_m = test::ate_rmse_m(dataset, dir / (label + ".txt"));
  }
  return result;
}

// heslam-loop-closer-proximity on this corridor loop (every frame, a loop accepted, ATE below
// kMaxAteOfPath of the path) is asserted on the run of Ros2TfEndToEnd.CorridorLoopTfComposesToThePosesAndOdomNeverJumps
// (tests/tools/ros2_tf_e2e_test.cpp): the same pipeline and arguments with heslam-ros2-bridge beside it, so the
// suite renders and runs it once.

// heslam-loop-closer, killed with SIGKILL once it has processed some keyframes (well before the loop):
// the supervisor restarts it, it rebuilds its map copy and keyframe database from DDS, and the loop is
// still closed where the camera comes back; every frame is in the trajectory.
TEST_F(CorridorLoop, BowLoopCloserKilledMidRunStillClosesTheLoopAndRemovesTheDrift) {
  const fs::path dir = dir_.path();
  auto supervisor =
      test::start_pipeline("synth", dataset_, dir, "killed", test_domain(), {"loop_closer=heslam-loop-closer"});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  bool killed = false;
  while (!killed && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    std::ifstream state(dir / "killed.loop");
    std::string line;
    int lines = 0;
    while (std::getline(state, line)) ++lines;
    const pid_t pid = test::child_pid(supervisor->pid(), kLoopCloserComm);
    if (lines >= 2 && pid != 0) {
      ::kill(pid, SIGKILL);
      killed = true;
    }
  }
  ASSERT_TRUE(killed) << "the loop closer never wrote its state file";
  ASSERT_EQ(test::finish(*supervisor), 0) << supervisor->out() << supervisor->err();
  const std::string output = supervisor->out() + supervisor->err();
  const eval::Trajectory truth = test::camera_ground_truth(dataset_);
  const double path_m = truth.path_length_m();
  const double ate_m = test::ate_rmse_m(dataset_, dir / "killed.txt");
  std::printf(
      "[ figures  ] corridor_loop %d frames, path %.1f m, heslam-loop-closer killed and restarted: ATE rmse "
      "%.1f mm (%.3f %%; %.1f mm without a loop closer), %d loop(s) accepted\n",
      kCorridorFrames, path_m, ate_m * 1e3, 100.0 * ate_m / path_m, kCorridorOdometryAteM * 1e3,
      loops_accepted(output));
  EXPECT_EQ(eval::read_trajectory(dir / "killed.txt").size(), truth.size());
  EXPECT_NE(output.find("restart"), std::string::npos) << output;
  EXPECT_GE(loops_accepted(output), 1) << output;
  EXPECT_LT(ate_m, 0.5 * kCorridorOdometryAteM);
  EXPECT_LT(ate_m, kMaxAteOfPath * path_m);
}

TEST(LoopCloserEndToEnd, RoomRevisitsWithoutFalseLoopsAndNoWorseAte) {
  const test::ScratchDir dir("room_loops");
  const fs::path dataset = dir.path() / "room";
  const std::string render_error = test::render_synth("room", 240, dataset, dir.path());
  ASSERT_TRUE(render_error.empty()) << render_error;
  const RunResult odometry = run("synth", dataset, dir.path(), "odometry", "none");
  ASSERT_EQ(odometry.code, 0) << odometry.output;
  const RunResult closed = run("synth", dataset, dir.path(), "bow", "heslam-loop-closer");
  ASSERT_EQ(closed.code, 0) << closed.output;
  std::printf("[ figures  ] room 240 frames: ATE rmse without loop closer %.2f mm, with %.2f mm, %d loop(s) accepted\n",
              odometry.ate_m * 1e3, closed.ate_m * 1e3, loops_accepted(closed.output));
  // A room seen from everywhere keeps every keyframe covisible: a loop accepted here would be wrong
  // or useless; whatever is accepted must not make the trajectory worse.
  EXPECT_LE(closed.ate_m, odometry.ate_m * 1.05);
}

TEST(LoopCloserEndToEnd, EurocMh01FullSystemNoWorseThanWithoutLoopCloser) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("mh01_loops");
  const RunResult without = run("euroc", dataset, dir.path(), "without", "none");
  ASSERT_EQ(without.code, 0) << without.output;
  const RunResult with = run("euroc", dataset, dir.path(), "with", "heslam-loop-closer");
  ASSERT_EQ(with.code, 0) << with.output;
  std::printf("[ figures  ] euroc_mh01_handheld: ATE rmse without loop closer %.3f mm, with %.3f mm, %d loop(s)\n",
              without.ate_m * 1e3, with.ate_m * 1e3, loops_accepted(with.output));
  EXPECT_EQ(with.poses, 160u);
  EXPECT_LE(with.ate_m, without.ate_m * 1.05);
}

// A loop closer started by hand against a running pipeline (same domain and namespace), as a user
// swapping in their own would: it gets the map written before it joined from the transient-local
// topics and processes the keyframes the mapper acknowledges (the recent acknowledgements are replayed
// to a late reader, so it catches up on those too).
TEST(LoopCloserEndToEnd, StartedByHandMidRunPicksUpTheMapFromDds) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("by_hand");
  const int domain = test_domain();
  auto supervisor = test::start_pipeline("euroc", dataset, dir.path(), "byhand", domain, {"loop_closer=none"});
  // Join once a third of the clip is tracked (the recorder's journal has a line per frame).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  int frames = 0;
  while (frames < 50 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::ifstream journal(dir.path() / "byhand.journal");
    std::string line;
    for (frames = 0; std::getline(journal, line);) ++frames;
  }
  ASSERT_GE(frames, 50) << "the pipeline never tracked 50 frames";
  // The replay pauses (SIGUSR1) while the loop closer loads its vocabulary and joins, so that on a
  // loaded machine the run cannot end before it subscribes; then it resumes (SIGUSR2). Joining
  // mid-run is what is tested, not the race with the end of the clip.
  const pid_t replay = test::child_pid(supervisor->pid(), "heslam-replay");
  ASSERT_GT(replay, 0) << "no replay process under the supervisor";
  kill(replay, SIGUSR1);
  // It joins the run (HESLAM_RUN_ID, printed by the supervisor): the run's components take its
  // corrections and acknowledgements as their own run's (a process of another run they refuse).
  static const std::regex run_line(R"(on domain \d+, namespace '[^']*', run ([0-9]+:[0-9]+);)");
  std::smatch run_match;
  const std::string supervisor_err = supervisor->err();
  ASSERT_TRUE(std::regex_search(supervisor_err, run_match, run_line)) << supervisor_err;
  setenv("HESLAM_RUN_ID", run_match[1].str().c_str(), 1);
  test::ChildProcess loop_closer(test::bin_dir() / "heslam-loop-closer", {"--domain", std::to_string(domain)},
                                 dir.path(), "loop_closer_by_hand");
  unsetenv("HESLAM_RUN_ID");
  for (const auto joined_by = std::chrono::steady_clock::now() + std::chrono::seconds(60);
       loop_closer.out().find("detector ") == std::string::npos &&
       loop_closer.err().find("detector ") == std::string::npos && !loop_closer.wait(std::chrono::milliseconds(0)) &&
       std::chrono::steady_clock::now() < joined_by;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  kill(replay, SIGUSR2);
  ASSERT_EQ(test::finish(*supervisor), 0) << supervisor->out() << supervisor->err();
  EXPECT_EQ(supervisor->err().find("another heslam run appeared"), std::string::npos) << supervisor->err();
  std::this_thread::sleep_for(std::chrono::seconds(1));  // the last acknowledgements reach it
  loop_closer.signal(SIGTERM);
  ASSERT_EQ(loop_closer.wait(test::kStopTimeout).value_or(-1), 0) << loop_closer.err();
  const std::string log = loop_closer.out() + loop_closer.err();
  static const std::regex map_copy(R"(map copy: (\d+) keyframes, (\d+) points)");
  static const std::regex processed(R"(processed (\d+) keyframes)");
  std::smatch copy_match;
  std::smatch processed_match;
  ASSERT_TRUE(std::regex_search(log, copy_match, map_copy)) << log;
  ASSERT_TRUE(std::regex_search(log, processed_match, processed)) << log;
  const int keyframes = std::stoi(copy_match[1]);
  const int processed_keyframes = std::stoi(processed_match[1]);
  std::printf(
      "[ figures  ] loop closer started by hand after %d frames: map copy %d keyframes, %s points; "
      "processed %d keyframes\n",
      frames, keyframes, copy_match[2].str().c_str(), processed_keyframes);
  // Every keyframe of the run is in its copy, including those written before it joined.
  EXPECT_EQ(keyframes, static_cast<int>(eval::read_trajectory(dir.path() / "byhand.keyframes.txt").size()));
  // It processes the keyframes acknowledged from then on and the recent ones the lockstep topic
  // replays to a late reader (here: all of them).
  EXPECT_GE(processed_keyframes, 1);
  EXPECT_LE(processed_keyframes, keyframes);
}

// The state file is a run file (runtime/run_journal.hpp): a forged line in it (right format, wrong
// checksum) is dropped and counted in one line naming the file, and the state it was slipped into is
// not resumed from (a snapshot missing a line is no state the loop closer was ever in).
TEST(LoopCloserProcess, AForgedStateFileLineIsDroppedAndCounted) {
  const test::ScratchDir dir("forged_state");
  const fs::path state = dir.path() / "run.loop";
  const auto start_loop_closer = [&] {
    return std::make_unique<test::ChildProcess>(
        test::bin_dir() / "heslam-loop-closer-proximity",
        std::vector<std::string>{"--domain", std::to_string(test_domain()), "--state-file", state.string()}, dir.path(),
        "loop_closer");
  };
  {
    auto loop_closer = start_loop_closer();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!fs::exists(state) && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    loop_closer->signal(SIGTERM);
    ASSERT_EQ(loop_closer->wait(test::kStopTimeout).value_or(-1), 0) << loop_closer->err();
  }
  std::ofstream(state, std::ios::app) << "loop 3 9 #3 0badf00d\n";  // a loop never closed
  auto loop_closer = start_loop_closer();
  const std::string expected =
      state.string() +
      ": 1 line dropped, not resumed from (1 failing their checksum, 0 out of sequence); starting afresh";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while ((loop_closer->out() + loop_closer->err()).find(expected) == std::string::npos &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  loop_closer->signal(SIGTERM);
  EXPECT_EQ(loop_closer->wait(test::kStopTimeout).value_or(-1), 0) << loop_closer->err();
  const std::string log = loop_closer->out() + loop_closer->err();
  EXPECT_NE(log.find(expected), std::string::npos) << log;
  EXPECT_EQ(log.find("loops closed"), std::string::npos) << log;  // no "resuming: ... loops closed"
}

}  // namespace
}  // namespace heslam
