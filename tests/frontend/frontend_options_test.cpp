// Frontend options: no config = the core defaults (the offline chain); fields map to the core structs;
// bad fields are one clear line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "components/core/image/yaml_option.hpp"
#include "components/core/tracking/settings_file.hpp"
#include "components/core/tracking/tracker_settings.hpp"
#include "components/frontend/frontend_options.hpp"
#include "runtime/config.hpp"
#include "test_support.hpp"

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

// A settings file of `text` in a scratch folder, removed with it.
class SettingsScratch {
 public:
  SettingsScratch()
      : dir_(std::filesystem::temp_directory_path() /
             ("heslam_settings_" + std::to_string(getpid()) + "_" + std::to_string(counter_++))) {
    std::filesystem::create_directories(dir_);
  }
  ~SettingsScratch() { std::filesystem::remove_all(dir_); }
  std::filesystem::path write(const std::string& text) const {
    const std::filesystem::path file = dir_ / "settings.yaml";
    std::ofstream(file) << "%YAML:1.0\n" << text;
    return file;
  }

 private:
  static inline int counter_ = 0;
  std::filesystem::path dir_;
};

FrontendOptions with_settings(const std::filesystem::path& file, const std::string& config_yaml = "") {
  return FrontendOptions::from_config(runtime::Config::parse(config_yaml, "frontend.yaml"),
                                      {"--settings", file.string()});
}

std::string reported(const FrontendOptions& options) { return describe_settings(options.features, options.tracker); }

TEST(FrontendOptions, SettingsFileReachesTheCoreOptions) {
  const SettingsScratch scratch;
  const FrontendOptions options = with_settings(
      scratch.write("HE.mode: \"clahe\"\nHE.stereo: \"separate\"\nHE.adaptiveOnBelow: 10.0\nHE.adaptiveOffAbove: 30.0\n"
                    "ORBextractor.nFeatures: 2000\n"
                    "Camera.fps: 10.0\nThDepth: 40.0\nTracker.ransacSeed: 7\n"),
      "lockstep:\n  wait_for_mapper: true\n  mapper_timeout_s: 2.5\n");
  EXPECT_EQ(options.features.he.mode, HeMode::kClahe);
  EXPECT_EQ(options.features.he.stereo, StereoPhotometry::kSeparate);
  EXPECT_EQ(options.features.he.adaptive_on_below, 10.0);
  EXPECT_EQ(options.features.he.adaptive_off_above, 30.0);
  EXPECT_EQ(options.features.orb.features, 2000);
  EXPECT_EQ(options.tracker.max_frames_between_keyframes, 10);  // ORB-SLAM2: mMaxFrames = fps
  EXPECT_EQ(options.tracker.close_depth_baselines, 40.0);       // ORB-SLAM2: ThDepth
  EXPECT_EQ(options.tracker.ransac_seed, 7u);
  EXPECT_EQ(options.tracker.reference_near_clip_weight, 0.0);  // the constant's value with a local mapper
  EXPECT_TRUE(options.settings_unused_keys.empty());
  EXPECT_TRUE(options.mapper_enabled);  // waiting for a mapper implies one
  EXPECT_TRUE(options.wait_for_mapper);
  EXPECT_FALSE(options.tracker.maintain_map);  // the mapper owns the map
  EXPECT_EQ(options.mapper_timeout.count(), 2500);
}

// The settings file's keys (docs/frontend.md, "Settings file keys": each with the reason a user would
// change it). Every other option is a constant of its Options struct.
const char* const kSettingsKeys[] = {"Camera.fps",
                                     "ThDepth",
                                     "Stereo.ThDepth",
                                     "ORBextractor.nFeatures",
                                     "ORBextractor.scaleFactor",
                                     "ORBextractor.nLevels",
                                     "ORBextractor.iniThFAST",
                                     "ORBextractor.minThFAST",
                                     "HE.mode",
                                     "HE.stereo",
                                     "HE.globalClipLimit",
                                     "HE.clipLimit",
                                     "HE.tilesX",
                                     "HE.tilesY",
                                     "HE.adaptiveOnBelow",
                                     "HE.adaptiveOffAbove",
                                     "Stereo.rowBand",
                                     "Pipeline.parallel",
                                     "Pipeline.pinThreads",
                                     "Pipeline.leftOnlyFeatures",
                                     "Tracker.stationaryTestChi2",
                                     "Tracker.rotationOnlyTestChi2",
                                     "Tracker.ransacSeed",
                                     "Tracker.revisitMinAgeS",
                                     "Tracker.revisitMinOldInlierShare"};

// The keys of the settings file before issue 33 that are constants now: a file still giving one (an
// older copy of a shipped file) is told it is not used, never silently ignored.
const char* const kFormerKeys[] = {"HE.saturationExcess",
                                   "HE.matchShiftFrom",
                                   "HE.matchShiftFull",
                                   "HE.matchGainFrom",
                                   "HE.toneFromMatches",
                                   "ORBextractor.cellSize",
                                   "ORBextractor.featuresByArea",
                                   "Stereo.maxDistance",
                                   "Stereo.sadHalfWindow",
                                   "Stereo.sadSearch",
                                   "Stereo.minDepthBaselines",
                                   "Stereo.sadOutlierFactor",
                                   "Stereo.relativeSadOutliers",
                                   "Stereo.sadNormalization",
                                   "Stereo.subpixelFit",
                                   "Stereo.clipEdgeRadius",
                                   "Stereo.clipEdgeMinFraction",
                                   "Pipeline.rightFeaturesFactor",
                                   "Tracker.minFeaturesToInitialize",
                                   "Tracker.minStereoPointsToInitialize",
                                   "Tracker.descriptorThresholdHigh",
                                   "Tracker.descriptorThresholdLow",
                                   "Tracker.checkOrientation",
                                   "Tracker.motionSearchRadius",
                                   "Tracker.minMotionMatches",
                                   "Tracker.referenceSearchRadius",
                                   "Tracker.referenceRatio",
                                   "Tracker.minReferenceMatches",
                                   "Tracker.minPoseInliers",
                                   "Tracker.localSearchRadius",
                                   "Tracker.localSearchRadiusRelocalized",
                                   "Tracker.localRatio",
                                   "Tracker.minViewCosine",
                                   "Tracker.localMapMaxKeyframes",
                                   "Tracker.localMapNeighboursPerKeyframe",
                                   "Tracker.minLocalMapInliers",
                                   "Tracker.minLocalMapInliersAfterRelocalization",
                                   "Tracker.poseOptimizationRounds",
                                   "Tracker.poseOptimizationIterations",
                                   "Tracker.disparitySigmaRatio",
                                   "Tracker.minFramesBetweenKeyframes",
                                   "Tracker.closeTrackedNeeded",
                                   "Tracker.closeUntrackedEnough",
                                   "Tracker.closeUntrackedNearClipWeight",
                                   "Tracker.referenceRatioStereo",
                                   "Tracker.referenceNearClipWeight",
                                   "Tracker.referenceRatioSingleKeyframe",
                                   "Tracker.minKeyframeInliers",
                                   "Tracker.newKeyframeMinPoints",
                                   "Tracker.relocalizationKeyframes",
                                   "Tracker.relocalizationRatio",
                                   "Tracker.minRelocalizationMatches",
                                   "Tracker.minRelocalizationInliers"};

// The reader looks up exactly the settings keys, no more: a new key needs its line in docs/frontend.md
// (and here), with the reason a user would change it.
TEST(FrontendOptions, TheReaderLooksUpExactlyTheSettingsKeys) {
  // What load_settings_file reads with (its own KeyLog would hide the lookups from one here).
  cv::FileStorage empty("%YAML:1.0\nViewer.PointSize: 2\n", cv::FileStorage::READ | cv::FileStorage::MEMORY);
  std::set<std::string> looked_up;
  {
    const yaml_option::KeyLog log;
    StereoFeaturePipelineOptions::from_yaml(empty.root(), "empty.yaml");
    TrackerOptions tracker;
    read_tracker_settings(empty.root(), "empty.yaml", tracker);
    looked_up = log.keys();
  }
  EXPECT_EQ(looked_up, std::set<std::string>(std::begin(kSettingsKeys), std::end(kSettingsKeys)));
  std::ifstream doc(heslam::test::source_dir() / "docs/frontend.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  // The settings table: from its header to the former keys' table.
  const std::size_t table = text.find("| Key | Default | Meaning | Change it when |");
  const std::size_t former = text.find("Former keys", table);
  ASSERT_NE(table, std::string::npos);
  ASSERT_NE(former, std::string::npos);
  const std::string rows = text.substr(table, former - table);
  for (const char* key : kSettingsKeys) {
    EXPECT_NE(rows.find(std::string("`") + key + "`"), std::string::npos) << key << ": its row in docs/frontend.md";
  }
}

// A user's edit of the settings file is never ignored. Each settings key, changed from the value
// config/camera/EuRoC.yaml gives it, changes the settings the frontend reports at start.
TEST(FrontendOptions, EachDocumentedSettingsKeyChangesWhatTheFrontendReports) {
  const std::filesystem::path euroc = heslam::test::source_dir() / "config/camera/EuRoC.yaml";
  std::ifstream in(euroc);
  const std::string base((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string baseline = reported(with_settings(euroc));
  // {key, value, the key whose line it replaces (ORB-SLAM3's Stereo.ThDepth replaces ThDepth)}
  const std::tuple<const char*, const char*, const char*> changes[] = {
      {"Camera.fps", "30.0", nullptr},
      {"ThDepth", "40.0", nullptr},
      {"Stereo.ThDepth", "40.0", "ThDepth"},
      {"ORBextractor.nFeatures", "1500", nullptr},
      {"ORBextractor.scaleFactor", "1.3", nullptr},
      {"ORBextractor.nLevels", "6", nullptr},
      {"ORBextractor.iniThFAST", "25", nullptr},
      {"ORBextractor.minThFAST", "5", nullptr},
      {"HE.mode", "\"global\"", nullptr},
      {"HE.stereo", "\"shared\"", nullptr},
      {"HE.globalClipLimit", "3.0", nullptr},
      {"HE.clipLimit", "4.0", nullptr},
      {"HE.tilesX", "4", nullptr},
      {"HE.tilesY", "4", nullptr},
      {"HE.adaptiveOnBelow", "20.0", nullptr},
      {"HE.adaptiveOffAbove", "40.0", nullptr},
      {"Stereo.rowBand", "3.0", nullptr},
      {"Pipeline.parallel", "0", nullptr},
      {"Pipeline.pinThreads", "0", nullptr},
      {"Pipeline.leftOnlyFeatures", "0.5", nullptr},
      {"Tracker.stationaryTestChi2", "0", nullptr},
      {"Tracker.rotationOnlyTestChi2", "0", nullptr},
      {"Tracker.ransacSeed", "7", nullptr},
      {"Tracker.revisitMinAgeS", "0", nullptr},
      {"Tracker.revisitMinOldInlierShare", "0.9", nullptr}};
  std::set<std::string> changed;
  for (const auto& [key, value, replaces] : changes) {
    changed.insert(key);
    // The key's line (or the line of the key it replaces) replaced, or appended when the file has none.
    std::string text = base;
    const std::string prefix = std::string("\n") + (replaces != nullptr ? replaces : key) + ":";
    const std::size_t at = text.find(prefix);
    if (at == std::string::npos) {
      text += std::string(key) + ": " + value + "\n";
    } else {
      const std::size_t end = text.find('\n', at + 1);
      text.replace(at + 1, end - at - 1, std::string(key) + ": " + value);
    }
    const SettingsScratch scratch;
    const std::filesystem::path file = scratch.write(text.substr(text.find('\n') + 1));  // without its %YAML line
    const FrontendOptions options = with_settings(file);
    EXPECT_NE(reported(options), baseline) << key << ": " << value;
    EXPECT_TRUE(options.settings_unused_keys.empty()) << key;
  }
  EXPECT_EQ(changed, std::set<std::string>(std::begin(kSettingsKeys), std::end(kSettingsKeys)));
}

// A former key (a constant now) in a settings file changes nothing and is named as not used.
TEST(FrontendOptions, EachFormerSettingsKeyIsReportedAsUnused) {
  const std::filesystem::path euroc = heslam::test::source_dir() / "config/camera/EuRoC.yaml";
  const FrontendOptions baseline = with_settings(euroc);
  std::ifstream in(euroc);
  const std::string base((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* key : kFormerKeys) {
    EXPECT_EQ(std::count(std::begin(kSettingsKeys), std::end(kSettingsKeys), std::string(key)), 0) << key;
    EXPECT_EQ(base.find(std::string("\n") + key + ":"), std::string::npos) << key << " still in EuRoC.yaml";
    const SettingsScratch scratch;
    // A value the old reader would have refused or that differs from the constant: neither matters now.
    const FrontendOptions options = with_settings(scratch.write(base.substr(base.find('\n') + 1) + key + ": 3\n"));
    EXPECT_EQ(options.settings_unused_keys, std::vector<std::string>{key});
    EXPECT_TRUE(options.features == baseline.features) << key;
    EXPECT_TRUE(options.tracker == baseline.tracker) << key;
  }
}

// A key nothing reads (a typo, ORB-SLAM2's viewer) is named; the config's old sections are an error
// that says where the option went.
TEST(FrontendOptions, UnusedSettingsKeysAreNamedAndOldConfigSectionsRefused) {
  const SettingsScratch scratch;
  const FrontendOptions options =
      with_settings(scratch.write("ORBextractor.nFeature: 900\nViewer.PointSize: 2\nCamera.fx: 400.0\n"));
  EXPECT_EQ(options.settings_unused_keys, (std::vector<std::string>{"ORBextractor.nFeature", "Viewer.PointSize"}));
  EXPECT_EQ(options.settings_camera_fx, 400.0);  // a calibration key: compared with the data's, not unused
  for (const char* section : {"he:\n  mode: clahe\n", "orb:\n  features: 900\n", "tracker:\n  ransac_seed: 3\n"}) {
    try {
      FrontendOptions::from_config(runtime::Config::parse(section, "frontend.yaml"));
      ADD_FAILURE() << "expected an error for " << section;
    } catch (const std::runtime_error& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find("settings file"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
}

// The error of reading `text` as the settings file: one line naming the file and the key.
void expect_error_naming_key(const std::string& text, const std::string& key) {
  const SettingsScratch scratch;
  const std::filesystem::path file = scratch.write(text);
  try {
    with_settings(file);
    FAIL() << "expected an error for " << key;
  } catch (const std::runtime_error& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find(key), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(FrontendOptions, BadSettingIsOneLineNamingFileAndKey) {
  expect_error_naming_key("ORBextractor.nLevels: 40\n", "ORBextractor.nLevels");
  expect_error_naming_key("Stereo.rowBand: 0.0\n", "Stereo.rowBand");
  expect_error_naming_key("Camera.fps: -5.0\n", "Camera.fps");
  expect_error_naming_key("Tracker.stationaryTestChi2: -1.0\n", "Tracker.stationaryTestChi2");
  const auto typo = runtime::Config::parse("lockstep:\n  wait_for_mapr: true\n", "frontend.yaml");
  FrontendOptions::from_config(typo);
  EXPECT_THROW(typo.reject_unknown(), std::runtime_error);
}

// An ORB-SLAM3 settings file (File.version "1.0") is read with ORB-SLAM3's meaning: its ORBextractor.*
// and Stereo.ThDepth reach the frontend, Camera1.* / Stereo.b are the calibration keys compared with the
// data's, and a typo is named as in an ORB-SLAM2 file.
TEST(FrontendOptions, OrbSlam3SettingsFileIsHonoured) {
  const SettingsScratch scratch;
  const FrontendOptions options = with_settings(scratch.write(
      "File.version: \"1.0\"\nCamera.type: \"PinHole\"\nCamera1.fx: 400.0\nCamera1.fy: 400.0\nCamera1.cx: 376.0\n"
      "Camera1.cy: 240.0\nCamera.width: 752\nCamera.height: 480\nCamera.fps: 10\nCamera.RGB: 1\nStereo.b: 0.1\n"
      "Stereo.ThDepth: 60.0\nORBextractor.nFeatures: 1300\nORBextractor.nFeaturess: 1400\nViewer.KeyFrameSize: "
      "0.05\n"));
  EXPECT_EQ(options.features.orb.features, 1300);
  EXPECT_EQ(options.tracker.close_depth_baselines, 60.0);
  EXPECT_EQ(options.tracker.max_frames_between_keyframes, 10);
  EXPECT_EQ(options.settings_unused_keys, (std::vector<std::string>{"ORBextractor.nFeaturess", "Viewer.KeyFrameSize"}));
  EXPECT_DOUBLE_EQ(options.settings_camera_fx, 400.0);
  EXPECT_NEAR(options.settings_camera_bf, 40.0, 1e-9);
  expect_error_naming_key("File.version: \"1.0\"\nCamera.type: \"Rectified\"\n", "Camera.type");
  expect_error_naming_key("ThDepth: 40.0\nStereo.ThDepth: 60.0\n", "Stereo.ThDepth");
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

// The EuRoC and synth settings files must not pin values that the core's defaults have since
// changed: they give exactly the options of no settings (the offline harness's chain).
// --mapping off is localization only: the tracker creates no keyframe; it needs a saved map
// (--localize), and the failure to relocalize names the user's map, not the working copy.
TEST(FrontendOptions, MappingOffIsLocalizationOnlyInTheSavedMap) {
  const runtime::Config config =
      runtime::Config::parse("mapper:\n  enabled: true\nvocabulary:\n  file: none\n", "frontend.yaml");
  EXPECT_TRUE(FrontendOptions::from_config(config, {"--mapper-map-file", "/run/x.map"}).tracker.create_keyframes);
  const FrontendOptions localization = FrontendOptions::from_config(
      config, {"--mapper-map-file", "/run/x.map", "--localize", "--mapping", "off", "--saved-map", "/maps/hall.map"});
  EXPECT_FALSE(localization.mapping);
  EXPECT_FALSE(localization.tracker.create_keyframes);
  EXPECT_EQ(never_relocalized_message(localization, 95),
            "never relocalized in the saved map (/maps/hall.map, loaded into /run/x.map): 95 frames, none tracked");
  try {
    FrontendOptions::from_config(config, {"--mapper-map-file", "/run/x.map", "--mapping", "off"});
    FAIL() << "--mapping off without --localize was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("--mapping off"), std::string::npos) << error.what();
  }
  EXPECT_THROW(FrontendOptions::from_config(config, {"--localize", "--mapper-map-file", "/x", "--mapping", "maybe"}),
               std::runtime_error);
}

// The atlas never starts a new map in a localization run (with or without mapping): a frame stays lost
// until it is relocalized in the saved map, and a run that never is still fails.
TEST(FrontendOptions, LocalizationRunsNeverStartANewMap) {
  const runtime::Config config =
      runtime::Config::parse("mapper:\n  enabled: true\nvocabulary:\n  file: none\n", "frontend.yaml");
  EXPECT_EQ(FrontendOptions::from_config(config, {"--mapper-map-file", "/run/x.map"}).tracker.new_map_after_ns,
            1'000'000'000);
  EXPECT_EQ(
      FrontendOptions::from_config(config, {"--mapper-map-file", "/run/x.map", "--localize"}).tracker.new_map_after_ns,
      0);
  EXPECT_EQ(FrontendOptions::from_config(config, {"--mapper-map-file", "/run/x.map", "--localize", "--mapping", "off"})
                .tracker.new_map_after_ns,
            0);
}

TEST(FrontendOptions, EurocAndSynthConfigsAreTheCoreDefaults) {
  const FrontendOptions defaults = FrontendOptions::from_config(runtime::Config::empty());
  for (const char* name : {"euroc", "synth"}) {
    const FrontendOptions options = FrontendOptions::from_config(
        runtime::Config::load(heslam::test::source_dir() / "config/frontend" / (std::string(name) + ".yaml")));
    EXPECT_EQ(options.features.he.mode, defaults.features.he.mode) << name;
    EXPECT_EQ(options.features.orb.features, defaults.features.orb.features) << name;
    EXPECT_EQ(options.features.stereo.max_distance, defaults.features.stereo.max_distance) << name;
    EXPECT_EQ(options.tracker.max_frames_between_keyframes, defaults.tracker.max_frames_between_keyframes) << name;
    EXPECT_EQ(options.mapper_enabled, defaults.mapper_enabled) << name;
  }
}

// Every option the shipped settings files give, field by field: the core defaults but for the
// few values each file is there to set (KITTI: 2000 features, a keyframe a second at 10 Hz; ORB-SLAM3's
// EuRoC file: its ThDepth 60). Pins the files across changes of which keys the reader reads.
TEST(FrontendOptions, ShippedSettingsFilesGiveExactlyTheirOptions) {
  const std::filesystem::path camera = heslam::test::source_dir() / "config/camera";
  const StereoFeaturePipelineOptions core_pipeline;
  const TrackerOptions core_tracker;
  StereoFeaturePipelineOptions kitti_pipeline;
  kitti_pipeline.orb.features = 2000;
  TrackerOptions kitti_tracker;
  kitti_tracker.max_frames_between_keyframes = 10;
  TrackerOptions orbslam3_tracker;
  orbslam3_tracker.close_depth_baselines = 60.0;
  const struct {
    const char* file;
    const StereoFeaturePipelineOptions& pipeline;
    const TrackerOptions& tracker;
  } shipped[] = {
      {"EuRoC.yaml", core_pipeline, core_tracker},        {"synth.yaml", core_pipeline, core_tracker},
      {"KITTI00-02.yaml", kitti_pipeline, kitti_tracker}, {"KITTI03.yaml", kitti_pipeline, kitti_tracker},
      {"KITTI04-12.yaml", kitti_pipeline, kitti_tracker}, {"EuRoC_ORB-SLAM3.yaml", core_pipeline, orbslam3_tracker}};
  for (const auto& [file, pipeline, tracker] : shipped) {
    const SettingsFile settings = load_settings_file(camera / file);
    EXPECT_TRUE(settings.pipeline == pipeline)
        << file << ": " << describe_settings(settings.pipeline, settings.tracker);
    EXPECT_TRUE(settings.tracker == tracker) << file << ": " << describe_settings(settings.pipeline, settings.tracker);
    EXPECT_TRUE(settings.unused_keys.empty()) << file << ": " << settings.unused_keys.front();
  }
}

TEST(FrontendOptions, ShippedConfigsLoad) {
  for (const auto& entry : std::filesystem::directory_iterator(heslam::test::source_dir() / "config/frontend")) {
    const std::string name = entry.path().filename().string();
    const auto config = runtime::Config::load(entry.path());
    EXPECT_NO_THROW(FrontendOptions::from_config(config)) << name;
    EXPECT_NO_THROW(config.reject_unknown()) << name;
  }
}

}  // namespace
}  // namespace heslam::frontend

namespace heslam::frontend {
namespace {

// imu.*: off by default (every stereo-only pipeline unchanged); the shipped inertial layer turns it on;
// --imu none wins over the config; a bad field is one line naming it.
TEST(FrontendOptions, InertialTrackingIsOffUnlessEnabledAndNoneWins) {
  EXPECT_FALSE(FrontendOptions::from_config(runtime::Config::empty()).inertial.enabled);
  const std::string yaml = "imu:\n  enabled: true\n  lockstep: false\n  blackout_max_s: 2.5\n  init_min_keyframes: 7\n";
  const FrontendOptions on = FrontendOptions::from_config(runtime::Config::parse(yaml, "frontend.yaml"));
  EXPECT_TRUE(on.inertial.enabled);
  EXPECT_FALSE(on.inertial.lockstep);
  EXPECT_DOUBLE_EQ(on.inertial.blackout_max_s, 2.5);
  EXPECT_EQ(on.inertial.init_min_keyframes, 7);
  const FrontendOptions none =
      FrontendOptions::from_config(runtime::Config::parse(yaml, "frontend.yaml"), {"--imu", "none"});
  EXPECT_FALSE(none.inertial.enabled);
  const FrontendOptions shipped =
      FrontendOptions::from_config(runtime::Config::load(heslam::test::source_dir() / "config/frontend/inertial.yaml"));
  EXPECT_TRUE(shipped.inertial.enabled);
  EXPECT_TRUE(shipped.inertial.lockstep);
  // The inertial pose optimization, once gravity is certain (docs/imu.md has the measurements behind these).
  EXPECT_TRUE(shipped.inertial.pose_optimization);
  EXPECT_DOUBLE_EQ(shipped.inertial.pose_optimization_max_gravity_stddev_deg, 0.05);
  EXPECT_DOUBLE_EQ(shipped.inertial.pose_prior_position_m, 0.003);
  EXPECT_DOUBLE_EQ(shipped.inertial.pose_prior_velocity_m_s, 0.03);
  try {
    FrontendOptions::from_config(
        runtime::Config::parse("imu:\n  pose_optimization_max_gravity_stddev_deg: -0.1\n", "frontend.yaml"));
    FAIL() << "a negative pose_optimization_max_gravity_stddev_deg was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("imu.pose_optimization_max_gravity_stddev_deg"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(FrontendOptions::from_config(runtime::Config::empty(), {"--imu", "maybe"}), std::runtime_error);
  try {
    FrontendOptions::from_config(runtime::Config::parse("imu:\n  blackout_max_s: -1\n", "frontend.yaml"));
    FAIL() << "a negative blackout_max_s was accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("imu.blackout_max_s"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace heslam::frontend
