// heslam-occupancy killed with SIGKILL mid-run and restarted by the supervisor rebuilds its map from its
// state folder (one keyframe cloud per file, replaced atomically) and the keyframes and states DDS
// keeps (transient-local): the saved grid (STEM.pgm + STEM.yaml) and cloud (STEM.ply) are byte-identical
// to an undisturbed run's. The synthetic room in lockstep, full system without a loop closer.
//
// The kill is made while the run is held (the replay paused with SIGUSR1, as the supervisor's space
// key does) and every keyframe made so far has its cloud on disk, and the run goes on (SIGUSR2) once
// the restarted process has its calibration again: a keyframe made while the process is down has no
// frame any more (the frontend never waits for it), which docs/occupancy.md states; this test is
// about what the process itself must keep. Every wait is on a state of the run, bounded against hangs.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "occupancy_run_watch.hpp"
#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;

constexpr int kRoomFrames = 150;
// Killed once this many keyframes exist (the room makes about one keyframe every 6 frames).
constexpr std::size_t kKillAfterKeyframes = 8;
constexpr seconds kStateTimeout{120};         // bound of a hung run, not a performance assertion
const char* const kComm = "heslam-occupanc";  // /proc comm: the first 15 characters

std::string file_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(OccupancyRestart, KilledMidRunItSavesTheGridAndCloudOfAnUndisturbedRun) {
  fs::path dataset;
  const std::string render_error = test::cached_synth("room", kRoomFrames, dataset);
  ASSERT_TRUE(render_error.empty()) << render_error;
  const test::ScratchDir dir("occupancy_restart");
  const std::vector<std::string> args{"occupancy=heslam-occupancy", "loop_closer=none"};

  {
    auto calm = test::start_pipeline("synth", dataset, dir.path(), "calm", test::exclusive_domain_id(), args);
    ASSERT_EQ(test::finish(*calm), 0) << calm->out() << calm->err();
  }

  const int domain = test::exclusive_domain_id();
  test::OccupancyRunWatch watch(domain, kStateTimeout);
  auto run = test::start_pipeline("synth", dataset, dir.path(), "killed", domain, args);
  ASSERT_TRUE(watch.until([&] { return watch.keyframe_ids.size() >= kKillAfterKeyframes; })) << run->err();
  const pid_t replay = test::child_pid(run->pid(), "heslam-replay");
  ASSERT_GT(replay, 0);
  ASSERT_EQ(kill(replay, SIGUSR1), 0);  // pause: the replay holds its next frame
  // Held: the frontend acknowledged the last frame published, and every keyframe has its cloud on disk.
  ASSERT_TRUE(watch.until([&] { return watch.settled(); }))
      << "frames " << watch.last_frame_seq.value_or(0) << ", done " << watch.last_done_seq.value_or(0) << ", keyframes "
      << watch.keyframe_ids.size() << ", clouds " << (watch.occupancy ? watch.occupancy->counter("clouds") : 0) << "\n"
      << run->err();
  const std::size_t clouds_before = watch.occupancy->counter("clouds");
  const pid_t victim = test::child_pid(run->pid(), kComm);
  ASSERT_GT(victim, 0);
  ASSERT_EQ(victim, watch.occupancy->pid);
  ASSERT_EQ(kill(victim, SIGKILL), 0);
  // Its state folder: one file per keyframe cloud (a culled keyframe's was removed).
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(dir.path() / "killed.occupancy")) {
    files += entry.path().extension() == ".cloud";
  }
  ASSERT_GT(files, 0u);
  // Restarted by the supervisor: a new pid, every cloud loaded from its state folder, the calibration taken.
  ASSERT_TRUE(watch.until([&] {
    return watch.occupancy && watch.occupancy->pid != victim && watch.occupancy->counter("calibrations") >= 1 &&
           watch.occupancy->counter("clouds_loaded") == files;
  })) << run->err();
  ASSERT_EQ(kill(replay, SIGUSR2), 0);  // resume
  ASSERT_EQ(test::finish(*run), 0) << run->out() << run->err();
  const std::string output = run->out() + run->err();
  EXPECT_NE(output.find("occupancy"), std::string::npos);

  // The run itself is the undisturbed one (lockstep), and so is the map.
  EXPECT_EQ(file_text(dir.path() / "killed.txt"), file_text(dir.path() / "calm.txt"));
  for (const char* extension : {".pgm", ".yaml", ".ply"}) {
    const std::string calm = file_text(dir.path() / (std::string("calm") + extension));
    std::string killed = file_text(dir.path() / (std::string("killed") + extension));
    // The YAML names its image: killed.pgm there, calm.pgm in the undisturbed run's.
    if (const std::size_t image = killed.find("image: killed.pgm"); image != std::string::npos) {
      killed.replace(image, std::string("image: killed.pgm").size(), "image: calm.pgm");
    }
    ASSERT_FALSE(calm.empty()) << extension;
    EXPECT_EQ(killed.size(), calm.size()) << extension;
    EXPECT_TRUE(killed == calm) << extension << " differs from the undisturbed run's";
  }
  std::printf(
      "[ figures  ] occupancy killed after %zu keyframe clouds (%zu cloud files), restarted; grid and cloud "
      "byte-identical to the undisturbed run's\n",
      clouds_before, files);
}

}  // namespace
}  // namespace heslam
