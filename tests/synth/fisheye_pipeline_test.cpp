// End to end on a fisheye stereo pair: heslam-synth renders the room through equidistant lenses
// (--camera fisheye), the replay publishes its equidistant calibration, the frontend rectifies it to a
// pinhole pair, and the full system (config/pipelines/synth.yaml, lockstep) tracks every frame with an
// ATE against the exact ground truth.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "child_process.hpp"
#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 300;  // the first half of the room preset's 600 frames
// Lockstep runs are deterministic: this run measured 8.80 mm (the 600-frame figure is in docs/tools/synth.md,
// Fisheye camera); the bound leaves room for another machine's floating point, not for a failure.
constexpr double kMaxAteM = 0.015;

TEST(FisheyePipeline, FullSystemTracksEveryFrameOfTheFisheyeRoom) {
  const test::ScratchDir dir("fisheye_pipeline");
  const fs::path dataset = dir.path() / "room_fisheye";
  test::ChildProcess synth(test::bin_dir() / "heslam-synth",
                           {"--preset", "room", "--camera", "fisheye", "--frames", std::to_string(kFrames), "--threads",
                            "2", "--no-events", "--out", dataset.string()},
                           dir.path(), "synth_fisheye");
  ASSERT_EQ(synth.wait(std::chrono::seconds(300)).value_or(-1), 0) << synth.err();

  auto supervisor = test::start_pipeline("synth", dataset, dir.path(), "run", test::exclusive_domain_id());
  const int code = test::finish(*supervisor, std::chrono::seconds(600));
  ASSERT_EQ(code, 0) << supervisor->out() << supervisor->err();
  const std::size_t poses = eval::read_trajectory(dir.path() / "run.txt").size();
  const int lost = test::lost_entries(dir.path() / "run.lost.txt");
  EXPECT_EQ(poses, static_cast<std::size_t>(kFrames));
  EXPECT_EQ(lost, 0);
  const double ate_m = test::ate_rmse_m(dataset, dir.path() / "run.txt");
  std::printf("[ figures  ] room through the fisheye camera, %d frames: %zu poses, %d lost, ATE rmse %.2f mm\n",
              kFrames, poses, lost, ate_m * 1e3);
  EXPECT_LT(ate_m, kMaxAteM);
}

}  // namespace
}  // namespace heslam
