// Frontend options: no config = the core defaults (the offline chain); fields map to the core structs;
// bad fields are one clear line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "components/frontend/frontend_options.hpp"
#include "runtime/config.hpp"

namespace heslam::frontend {
namespace {

TEST(FrontendOptions, EmptyConfigKeepsTheCoreDefaults) {
  const FrontendOptions options = FrontendOptions::from_config(runtime::Config::empty());
  const StereoFeaturePipelineOptions features;
  const TrackerOptions tracker;
  EXPECT_EQ(options.features.he.mode, features.he.mode);
  EXPECT_EQ(options.features.orb.features, features.orb.features);
  EXPECT_EQ(options.features.orb.levels, features.orb.levels);
  EXPECT_EQ(options.features.stereo.max_distance, features.stereo.max_distance);
  EXPECT_EQ(options.features.parallel, features.parallel);
  EXPECT_EQ(options.tracker.max_frames_between_keyframes, tracker.max_frames_between_keyframes);
  EXPECT_EQ(options.tracker.ransac_seed, tracker.ransac_seed);
  EXPECT_TRUE(options.tracker.maintain_map);
  EXPECT_FALSE(options.mapper_enabled);
  EXPECT_FALSE(options.wait_for_mapper);
}

TEST(FrontendOptions, FieldsReachTheCoreOptions) {
  const auto config = runtime::Config::parse(
      "he:\n  mode: clahe\n  stereo: separate\n  match_shift_from: 10\n  match_shift_full: 30\n"
      "orb:\n  features: 2000\nstereo:\n  clip_masked_sad: true\n  cost: census\n"
      "tracker:\n  max_frames_between_keyframes: 10\n  reference_near_clip_weight: 0.25\n"
      "lockstep:\n  wait_for_mapper: true\n  mapper_timeout_s: 2.5\n",
      "test.yaml");
  const FrontendOptions options = FrontendOptions::from_config(config);
  config.reject_unknown();
  EXPECT_EQ(options.features.he.mode, HeMode::kClahe);
  EXPECT_EQ(options.features.he.stereo, StereoPhotometry::kSeparate);
  EXPECT_EQ(options.features.he.match_shift_from, 10.0);
  EXPECT_EQ(options.features.he.match_shift_full, 30.0);
  EXPECT_EQ(options.features.orb.features, 2000);
  EXPECT_EQ(options.tracker.max_frames_between_keyframes, 10);
  EXPECT_TRUE(options.features.stereo.clip_masked_sad);
  EXPECT_EQ(options.features.stereo.cost, StereoMatcherOptions::MatchCost::kCensus);
  EXPECT_EQ(options.tracker.reference_near_clip_weight, 0.25);
  EXPECT_TRUE(options.mapper_enabled);  // waiting for a mapper implies one
  EXPECT_TRUE(options.wait_for_mapper);
  EXPECT_FALSE(options.tracker.maintain_map);  // the mapper owns the map
  EXPECT_EQ(options.mapper_timeout.count(), 2500);
}

// The error of reading `yaml` as frontend.yaml: one line naming the file and the field.
void expect_error_naming_field(const std::string& yaml, const std::string& field) {
  try {
    FrontendOptions::from_config(runtime::Config::parse(yaml, "frontend.yaml"));
    FAIL() << "expected an error for " << field;
  } catch (const std::runtime_error& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("frontend.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find(field), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(FrontendOptions, BadFieldIsOneLineNamingFileAndField) {
  expect_error_naming_field("orb:\n  levels: 40\n", "orb.levels");
  expect_error_naming_field("stereo:\n  cost: ssd\n", "stereo.cost");
  const auto typo = runtime::Config::parse("orb:\n  levle: 4\n", "frontend.yaml");
  FrontendOptions::from_config(typo);
  EXPECT_THROW(typo.reject_unknown(), std::runtime_error);
}

// vocabulary.file: empty = the build's default vocabulary, none = no vocabulary, a missing or
// malformed file one line naming it.
TEST(FrontendOptions, VocabularyFileDefaultNoneAndBadFiles) {
  const FrontendOptions defaults = FrontendOptions::from_config(runtime::Config::empty());
  ASSERT_NE(defaults.vocabulary, nullptr) << "the build's default vocabulary (heslam-default-vocabulary)";
  EXPECT_GT(defaults.vocabulary->word_count(), 0u);
  const auto none = runtime::Config::parse("vocabulary:\n  file: none\n", "frontend.yaml");
  EXPECT_EQ(FrontendOptions::from_config(none).vocabulary, nullptr);
  none.reject_unknown();

  const auto scratch = std::filesystem::temp_directory_path() / ("heslam_vocab_option_" + std::to_string(getpid()));
  std::filesystem::create_directories(scratch);
  {
    std::ofstream malformed(scratch / "bad.txt");
    malformed << "10 6 0 0\n0 0 1 2 3\n";
  }
  for (const std::string& file : {(scratch / "missing.hvoc").string(), (scratch / "bad.txt").string()}) {
    const auto config = runtime::Config::parse("vocabulary:\n  file: " + file + "\n", "frontend.yaml");
    try {
      FrontendOptions::from_config(config);
      ADD_FAILURE() << "expected an error for " << file;
    } catch (const std::runtime_error& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find(file), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
    }
  }
  std::filesystem::remove_all(scratch);
}

// The EuRoC and synth configs must not pin values that the core's defaults have since changed:
// they give exactly the options of no config (the offline harness's chain).
TEST(FrontendOptions, EurocAndSynthConfigsAreTheCoreDefaults) {
  const FrontendOptions defaults = FrontendOptions::from_config(runtime::Config::empty());
  for (const char* name : {"euroc", "synth"}) {
    const FrontendOptions options = FrontendOptions::from_config(
        runtime::Config::load(std::filesystem::path(HESLAM_SOURCE_DIR) / "config/frontend" / (std::string(name) + ".yaml")));
    EXPECT_EQ(options.features.he.mode, defaults.features.he.mode) << name;
    EXPECT_EQ(options.features.orb.features, defaults.features.orb.features) << name;
    EXPECT_EQ(options.features.stereo.max_distance, defaults.features.stereo.max_distance) << name;
    EXPECT_EQ(options.tracker.max_frames_between_keyframes, defaults.tracker.max_frames_between_keyframes) << name;
    EXPECT_EQ(options.mapper_enabled, defaults.mapper_enabled) << name;
  }
}

TEST(FrontendOptions, ShippedConfigsLoad) {
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(HESLAM_SOURCE_DIR) / "config/frontend")) {
    const std::string name = entry.path().filename().string();
    const auto config = runtime::Config::load(entry.path());
    EXPECT_NO_THROW(FrontendOptions::from_config(config)) << name;
    EXPECT_NO_THROW(config.reject_unknown()) << name;
  }
}

}  // namespace
}  // namespace heslam::frontend
