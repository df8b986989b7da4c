// heslam-viewer started by hand beside a synthetic-room run (synth pipeline, lockstep, own domain)
// ends by itself when the run ends, with its final pictures written; and the pipeline files pass the
// viewer's snapshot period, fit and ground truth through their arguments.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "pipeline_runs.hpp"
#include "runtime/supervisor/pipeline.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using test::ChildProcess;

constexpr int kFrames = 40;
// Bounds of a hung process, not performance assertions.
constexpr std::chrono::seconds kViewerReady{20};
constexpr std::chrono::seconds kViewerEnd{30};

TEST(ViewerRunEnd, AViewerStartedByHandExitsWhenTheRunEnds) {
  fs::path dataset;
  ASSERT_EQ(test::cached_synth("room", kFrames, dataset), "");
  const test::ScratchDir dir("viewer_run_end");
  const int domain = test::exclusive_domain_id();

  ChildProcess viewer(test::bin_dir() / "heslam-viewer",
                      {"--domain", std::to_string(domain), "--headless", "--out", (dir.path() / "pictures").string()},
                      dir.path(), "viewer");
  const auto ready_deadline = std::chrono::steady_clock::now() + kViewerReady;
  while (viewer.err().find("info: headless") == std::string::npos &&
         std::chrono::steady_clock::now() < ready_deadline && !viewer.wait(std::chrono::milliseconds(0))) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_NE(viewer.err().find("info: headless"), std::string::npos) << viewer.out() << viewer.err();

  auto run = test::start_pipeline("synth", dataset, dir.path(), "run", domain, {"loop_closer=none"});
  ASSERT_EQ(test::finish(*run), 0) << run->out() << run->err();
  const std::optional<int> code = viewer.wait(kViewerEnd);
  if (!code) {
    viewer.signal(SIGKILL);
    viewer.wait(kViewerEnd);
  }
  ASSERT_TRUE(code.has_value()) << "the viewer was still running " << kViewerEnd.count() << " s after the run ended\n"
                                << viewer.err();
  EXPECT_EQ(*code, 0) << viewer.err();
  EXPECT_NE(viewer.err().find("the supervisor (supervisor) is ending the run"), std::string::npos) << viewer.err();
  EXPECT_TRUE(fs::exists(dir.path() / "pictures/map_final.png")) << viewer.err();
  EXPECT_TRUE(fs::exists(dir.path() / "pictures/viewer_stats.txt")) << viewer.err();
}

// The viewer's command line in every pipeline that can start one.
TEST(ViewerPipelineArgs, SnapshotPeriodFitAndGroundTruthReachTheViewer) {
  const test::ScratchDir dir("viewer_pipeline_args");
  int pipelines_with_a_viewer = 0;
  for (const std::string name : {"euroc", "euroc_realtime", "kitti", "kitti_realtime", "synth"}) {
    SCOPED_TRACE(name);
    supervisor::PipelineOverrides overrides;
    overrides.args = {{"dataset", dir.path().string()}, {"viewer", "heslam-viewer"},
                      {"snapshot_every", "2"},          {"viewer_fit", "map"},
                      {"gt", "/data/gt.csv"},           {"gt_extrinsic", "/data/s.yaml"}};
    const supervisor::LoadResult result = supervisor::load_pipeline(
        test::source_dir() / "config/pipelines" / (name + ".yaml"), overrides, test::bin_dir());
    for (const std::string& problem : result.problems) ADD_FAILURE() << problem;
    for (const supervisor::ComponentSpec& spec : result.pipeline.components) {
      if (spec.name != "viewer") continue;
      ++pipelines_with_a_viewer;
      const auto value_of = [&](const std::string& flag) {
        const auto it = std::find(spec.args.begin(), spec.args.end(), flag);
        return it == spec.args.end() || it + 1 == spec.args.end() ? std::string("(missing)") : *(it + 1);
      };
      EXPECT_EQ(value_of("--snapshot-every"), "2");
      EXPECT_EQ(value_of("--fit"), "map");
      EXPECT_EQ(value_of("--gt"), "/data/gt.csv");
      EXPECT_EQ(value_of("--gt-extrinsic"), "/data/s.yaml");
    }
  }
  EXPECT_EQ(pipelines_with_a_viewer, 5);
}

}  // namespace
}  // namespace heslam
