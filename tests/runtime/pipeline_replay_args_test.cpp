// The shipped pipeline files as a user drives them (issue 39): every pipeline that runs heslam-replay
// takes the replay's controls as arguments (start_offset_s, duration_s, start_paused, loop; rate in
// real time) and passes them to it; lockstep files stay lockstep; the supervisor's start line names
// the run's mode; a loop closer that is not one says which ones are.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "runtime/supervisor/pipeline.hpp"
#include "runtime/supervisor/supervisor.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// Whether `args` holds `flag` directly followed by `value`.
bool has_pair(const std::vector<std::string>& args, const std::string& flag, const std::string& value) {
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == flag && args[i + 1] == value) return true;
  }
  return false;
}

bool has(const std::vector<std::string>& args, const std::string& flag) {
  return std::find(args.begin(), args.end(), flag) != args.end();
}

supervisor::LoadResult load(const std::string& pipeline, std::map<std::string, std::string> args,
                            const supervisor::PipelineOverrides& base = {}) {
  supervisor::PipelineOverrides overrides = base;
  overrides.args = std::move(args);
  return supervisor::load_pipeline(test::source_dir() / "config/pipelines" / (pipeline + ".yaml"), overrides,
                                   test::bin_dir());
}

TEST(PipelineReplayArgs, EveryReplayPipelineTakesTheReplaysControls) {
  test::ScratchDir dir("pipeline_replay_args");
  int replay_pipelines = 0;
  for (const auto& entry : fs::directory_iterator(test::source_dir() / "config/pipelines")) {
    const std::string name = entry.path().stem().string();
    if (name.rfind("camera", 0) == 0) continue;    // heslam-camera: a live source, no replay controls
    if (name.starts_with("ros2_input")) continue;  // its source is heslam-ros2-input (a ROS 2 camera), not the replay
    // several agents: one replay each, which end the run together (on_exit: shutdown_with_all; docs/agents.md)
    if (name.find("agents") != std::string::npos) continue;
    SCOPED_TRACE(name);
    const bool real_time = name.find("realtime") != std::string::npos || name == "replay_spy";
    std::map<std::string, std::string> args = {{"dataset", dir.path().string()},
                                               {"start_offset_s", "3"},
                                               {"duration_s", "5"},
                                               {"start_paused", "on"},
                                               {"loop", "on"}};
    if (real_time) args["rate"] = "2";
    const supervisor::LoadResult result = load(name, args);
    for (const std::string& problem : result.problems) ADD_FAILURE() << problem;
    const auto replay = std::find_if(result.pipeline.components.begin(), result.pipeline.components.end(),
                                     [](const auto& spec) { return spec.executable.filename() == "heslam-replay"; });
    ASSERT_NE(replay, result.pipeline.components.end());
    ++replay_pipelines;
    EXPECT_TRUE(has_pair(replay->args, "--start-offset", "3"));
    EXPECT_TRUE(has_pair(replay->args, "--duration", "5"));
    EXPECT_TRUE(has_pair(replay->args, "--start-paused-mode", "on"));
    EXPECT_TRUE(has_pair(replay->args, "--loop-mode", "on"));
    EXPECT_TRUE(replay->pausable) << "space on the supervisor's terminal pauses it";
    EXPECT_TRUE(replay->shutdown_on_exit);
    if (real_time) {
      EXPECT_TRUE(has_pair(replay->args, "--rate", "2"));
      EXPECT_FALSE(has(replay->args, "--lockstep"));
    } else {
      EXPECT_TRUE(has(replay->args, "--lockstep"));
      EXPECT_FALSE(has(replay->args, "--rate"));
    }
    // The defaults are the replay's own: from the start, to the end, playing, once.
    const supervisor::LoadResult defaults = load(name, {{"dataset", dir.path().string()}});
    const auto plain = std::find_if(defaults.pipeline.components.begin(), defaults.pipeline.components.end(),
                                    [](const auto& spec) { return spec.executable.filename() == "heslam-replay"; });
    ASSERT_NE(plain, defaults.pipeline.components.end());
    EXPECT_TRUE(has_pair(plain->args, "--start-offset", "0"));
    EXPECT_TRUE(has_pair(plain->args, "--duration", "0"));
    EXPECT_TRUE(has_pair(plain->args, "--start-paused-mode", "off"));
    EXPECT_TRUE(has_pair(plain->args, "--loop-mode", "off"));
  }
  // with euroc_inertial, euroc_inertial_realtime, synth_inertial, euroc_session, synth_session
  EXPECT_EQ(replay_pipelines, 17);
}

TEST(PipelineReplayArgs, TheStartLineNamesTheMode) {
  test::ScratchDir dir("pipeline_mode");
  const std::string dataset = dir.path().string();
  EXPECT_EQ(supervisor::describe_run_mode(load("euroc", {{"dataset", dataset}}).pipeline),
            "lockstep, plain DDS (not secure), every component on this host");
  EXPECT_EQ(supervisor::describe_run_mode(load("euroc_realtime", {{"dataset", dataset}, {"rate", "2"}}).pipeline),
            "real time (rate 2), plain DDS (not secure), every component on this host");
  supervisor::PipelineOverrides camera;
  camera.host = "camera";
  EXPECT_EQ(supervisor::describe_run_mode(load("euroc", {{"dataset", dataset}}, camera).pipeline),
            "lockstep, plain DDS (not secure), host 'camera' runs recorder, frontend, replay; elsewhere: "
            "local_mapper, loop_closer");
  supervisor::PipelineOverrides only;
  only.only = {"recorder", "frontend"};
  EXPECT_EQ(supervisor::describe_run_mode(load("euroc_odometry", {{"dataset", dataset}}, only).pipeline),
            "lockstep, plain DDS (not secure), this host runs recorder, frontend; elsewhere: replay");
}

TEST(PipelineReplayArgs, AWrongLoopCloserListsTheChoices) {
  test::ScratchDir dir("pipeline_loop_closer");
  const supervisor::LoadResult result = load("euroc", {{"dataset", dir.path().string()}, {"loop_closer", "proximity"}});
  ASSERT_FALSE(result.problems.empty());
  std::string problems;
  for (const std::string& problem : result.problems) problems += problem + "\n";
  EXPECT_NE(problems.find("executable 'proximity' not found (looked in " + test::bin_dir().string() +
                          " and $PATH); --arg loop_closer takes heslam-loop-closer, heslam-loop-closer-proximity, "
                          "or none"),
            std::string::npos)
      << problems;
}

}  // namespace
}  // namespace heslam
