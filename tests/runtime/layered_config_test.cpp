// Layered configs: a user's file overlays the shipped one field by field (runtime/config.hpp), and every
// shipped pipeline lays its --arg X_config file over its own config instead of replacing it.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <stdexcept>

#include "runtime/config.hpp"
#include "runtime/supervisor/pipeline.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using runtime::Config;

std::string error_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

class LayeredConfig : public ::testing::Test {
 protected:
  fs::path write(const std::string& relative, const std::string& text) {
    const fs::path file = dir_.path() / relative;
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
    return file;
  }
  test::ScratchDir dir_{"layered_config"};
};

TEST_F(LayeredConfig, ALaterFileOverlaysTheEarlierFieldByField) {
  const fs::path shipped = write("shipped/frontend.yaml",
                                 "mapper:\n  enabled: true\nlockstep:\n  wait_for_mapper: true\n"
                                 "settings:\n  file: ../camera/EuRoC.yaml\nvocabulary:\n  file: voc.txt\n");
  const fs::path user = write("user/mine.yaml", "vocabulary:\n  file: none\nlockstep:\n  wait_for_mapper: false\n");
  const Config config = Config::load(std::vector{shipped, user});
  EXPECT_TRUE(config.get_bool("mapper.enabled", false));            // only in the shipped file
  EXPECT_FALSE(config.get_bool("lockstep.wait_for_mapper", true));  // the user's value wins
  EXPECT_EQ(config.get_string("vocabulary.file", ""), "none");
  // A relative path is relative to the file it came from.
  EXPECT_EQ(config.get_path("settings.file", ""), dir_.path() / "shipped/../camera/EuRoC.yaml");
  EXPECT_NO_THROW(config.reject_unknown());
  EXPECT_TRUE(Config::load(std::vector<fs::path>{}).has("anything") == false);
}

TEST_F(LayeredConfig, ErrorsAndTyposNameTheFileTheyAreIn) {
  const fs::path shipped = write("shipped.yaml", "mapper:\n  enabled: true\nspeed: 2\n");
  const fs::path user = write("mine.yaml", "mapper:\n  enabled: maybe\n");
  const Config config = Config::load(std::vector{shipped, user});
  EXPECT_EQ(error_of([&] { config.get_bool("mapper.enabled", false); }),
            user.string() + ": field 'mapper.enabled': expected true or false, got 'maybe'");
  EXPECT_EQ(error_of([&] { config.get_int("speed", 0, 5, 9); }),
            shipped.string() + ": field 'speed': expected an integer in [5, 9], got 2");

  const fs::path typo = write("typo.yaml", "mapper:\n  enabeld: false\n");
  const Config with_typo = Config::load(std::vector{shipped, typo});
  with_typo.get_bool("mapper.enabled", false);
  with_typo.get_int("speed", 0);
  EXPECT_EQ(error_of([&] { with_typo.reject_unknown(); }),
            typo.string() + ": unknown field 'mapper.enabeld' (no such option)");
}

// The trap the issue found: --arg frontend_config=FILE holding one field replaced the pipeline's frontend
// config, so mapper.enabled was lost while the mapper ran. Every shipped pipeline now lays the file over
// its own config: the shipped wiring stays, the user's field wins.
TEST_F(LayeredConfig, EveryShippedPipelineLaysTheUsersComponentConfigOverItsOwn) {
  const fs::path user_frontend = write("frontend_overlay.yaml", "vocabulary:\n  file: none\n");
  const fs::path user_mapper = write("mapper_overlay.yaml", "sync_writes: true\n");
  int pipelines_with_a_mapper = 0;
  for (const auto& entry : fs::directory_iterator(test::source_dir() / "config/pipelines")) {
    const std::string name = entry.path().stem().string();
    if (name == "replay_spy") continue;  // no component configs
    SCOPED_TRACE(name);
    supervisor::PipelineOverrides overrides;
    overrides.args = {{"frontend_config", user_frontend.string()}};
    // A camera pipeline's input is its source (heslam-camera), ros2_input*'s a ROS 2 camera
    // (heslam-ros2-input), the others' a dataset.
    if (name.rfind("camera", 0) == 0) overrides.args["source"] = dir_.path().string();
    if (name.rfind("camera", 0) != 0 && !name.starts_with("ros2_input"))
      overrides.args["dataset"] = dir_.path().string();
    const bool has_mapper = name.find("odometry") == std::string::npos;
    const bool inertial = name.find("inertial") != std::string::npos;  // a shipped inertial layer
    if (has_mapper) overrides.args["mapper_config"] = user_mapper.string();
    const supervisor::LoadResult result = supervisor::load_pipeline(entry.path(), overrides, test::bin_dir());
    for (const std::string& problem : result.problems) ADD_FAILURE() << problem;
    for (const supervisor::ComponentSpec& spec : result.pipeline.components) {
      if (spec.name == "frontend") {
        // The shipped config, the inertial layer in the inertial pipelines, the user's last.
        ASSERT_EQ(spec.configs.size(), inertial ? 3u : 2u);
        EXPECT_EQ(spec.configs.back(), user_frontend);
        const Config frontend = Config::load(spec.configs);
        EXPECT_EQ(frontend.get_bool("mapper.enabled", false), has_mapper);
        EXPECT_EQ(frontend.get_string("vocabulary.file", ""), "none");
      } else if (spec.name == "local_mapper") {
        ++pipelines_with_a_mapper;
        // The shipped config, the inertial local BA's layer in the inertial pipelines, the user's last.
        ASSERT_EQ(spec.configs.size(), inertial ? 3u : 2u);
        EXPECT_EQ(spec.configs.back(), user_mapper);
      }
    }
    // Without the argument, the shipped files alone.
    overrides.args.erase("frontend_config");
    overrides.args.erase("mapper_config");
    for (const supervisor::ComponentSpec& spec :
         supervisor::load_pipeline(entry.path(), overrides, test::bin_dir()).pipeline.components) {
      if (spec.name == "frontend") {
        EXPECT_EQ(spec.configs.size(), inertial ? 2u : 1u);
      } else if (spec.name == "local_mapper") {
        EXPECT_EQ(spec.configs.size(), inertial ? 2u : 1u);
      }
    }
  }
  EXPECT_GE(pipelines_with_a_mapper, 6);
}

// Every shipped pipeline with a local mapper (the full system) can start heslam-occupancy
// (--arg occupancy=heslam-occupancy; default none) with its shipped layers and the user's
// occupancy_config last, and its stop timeout from --arg occupancy_stop_timeout_s (180 s by default).
TEST_F(LayeredConfig, EveryFullSystemPipelineStartsTheOccupancyWithTheUsersLayerAndStopTimeout) {
  const fs::path user_occupancy = write("occupancy_overlay.yaml", "voxel:\n  resolution_m: 0.1\n");
  int with_occupancy = 0;
  for (const auto& entry : fs::directory_iterator(test::source_dir() / "config/pipelines")) {
    const std::string name = entry.path().stem().string();
    if (name == "replay_spy" || name.find("odometry") != std::string::npos) continue;
    supervisor::PipelineOverrides overrides;
    if (name.rfind("camera", 0) == 0) overrides.args["source"] = dir_.path().string();
    if (name.rfind("camera", 0) != 0 && !name.starts_with("ros2_input"))
      overrides.args["dataset"] = dir_.path().string();
    // The localization, session and two-agent pipelines have no occupancy process (yet).
    std::ifstream in(entry.path());
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (text.find("$(arg occupancy)") == std::string::npos) continue;
    SCOPED_TRACE(name);
    ++with_occupancy;
    // Default: none, so no occupancy process at all.
    {
      const supervisor::LoadResult result = supervisor::load_pipeline(entry.path(), overrides, test::bin_dir());
      for (const std::string& problem : result.problems) ADD_FAILURE() << problem;
      for (const supervisor::ComponentSpec& spec : result.pipeline.components) EXPECT_NE(spec.name, "occupancy");
    }
    overrides.args["occupancy"] = "heslam-occupancy";
    for (const bool user : {false, true}) {
      if (user) {
        overrides.args["occupancy_config"] = user_occupancy.string();
        overrides.args["occupancy_stop_timeout_s"] = "900";
      }
      const supervisor::LoadResult result = supervisor::load_pipeline(entry.path(), overrides, test::bin_dir());
      for (const std::string& problem : result.problems) ADD_FAILURE() << problem;
      bool found = false;
      for (const supervisor::ComponentSpec& spec : result.pipeline.components) {
        if (spec.name != "occupancy") continue;
        found = true;
        ASSERT_GE(spec.configs.size(), 2u);
        EXPECT_EQ(spec.configs.front().filename(), "default.yaml");
        EXPECT_EQ(spec.configs.back() == user_occupancy, user);
        const Config occupancy = Config::load(spec.configs);
        EXPECT_EQ(occupancy.get_double("voxel.resolution_m", 0.0), user ? 0.1 : name.starts_with("kitti") ? 0.2 : 0.05);
        EXPECT_FALSE(occupancy.get_string("settings.file", "").empty());
        // The real-time pipelines' worker takes only CPU time nobody else wants (real_time.yaml).
        const bool real_time = name.find("realtime") != std::string::npos || name.starts_with("ros2_input");
        EXPECT_EQ(occupancy.get_bool("idle_priority", false), real_time);
        ASSERT_TRUE(spec.stop_timeout_s.has_value());
        EXPECT_EQ(*spec.stop_timeout_s, user ? 900.0 : 180.0);
      }
      EXPECT_TRUE(found);
    }
    overrides.args["occupancy_stop_timeout_s"] = "soon";
    const supervisor::LoadResult bad = supervisor::load_pipeline(entry.path(), overrides, test::bin_dir());
    ASSERT_EQ(bad.problems.size(), 1u);
    EXPECT_NE(bad.problems.front().find(".stop_timeout_s': expected seconds in [0.1, 3600], got 'soon'"),
              std::string::npos)
        << bad.problems.front();
  }
  // euroc, euroc_realtime, euroc_inertial(_realtime), kitti(_realtime), synth(_inertial), camera_realtime,
  // ros2_input(_inertial).
  EXPECT_EQ(with_occupancy, 11);
}

}  // namespace
}  // namespace heslam
