// heslam-local-mapper's options: the YAML config and the command line, and what each refuses.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "components/local_mapper/mapper_process_options.hpp"

namespace heslam::local_mapper {
namespace {

TEST(MapperOptions, ConfigAndCommandLine) {
  const runtime::Config config = runtime::Config::parse(
      "bundle_adjustment: {threads: 2, second_pass_iterations: 4}\nsave_every_keyframes: 3\n"
      "fusion: {enabled: false}\nmap_file: \"\"\nbatch_map_writes: false\n",
      "mapper.yaml");
  const MapperProcessOptions options = MapperProcessOptions::from_config(config, {"--map-file", "/tmp/a.map"});
  EXPECT_EQ(options.mapper.bundle_adjustment.num_threads, 2);
  EXPECT_EQ(options.mapper.bundle_adjustment.second_pass_iterations, 4);
  EXPECT_EQ(options.mapper.bundle_adjustment.first_pass_iterations, 5);  // ORB-SLAM2 default kept
  EXPECT_FALSE(options.mapper.enable_fusion);
  EXPECT_EQ(options.save_every_keyframes, 3);
  EXPECT_EQ(options.map_file, "/tmp/a.map");
  EXPECT_TRUE(options.load_map.empty());
  EXPECT_FALSE(options.batch_map_writes);
  EXPECT_TRUE(MapperProcessOptions::from_config(runtime::Config::empty(), {}).batch_map_writes);  // the default

  const runtime::Config bad = runtime::Config::parse("bundle_adjustment: {threads: 0}\n", "mapper.yaml");
  try {
    MapperProcessOptions::from_config(bad, {});
    FAIL() << "expected a rejection";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("bundle_adjustment.threads"), std::string::npos) << error.what();
  }
  EXPECT_THROW(MapperProcessOptions::from_config(runtime::Config::empty(), {"--load-map"}), std::runtime_error);
  EXPECT_THROW(MapperProcessOptions::from_config(runtime::Config::empty(), {"--bogus"}), std::runtime_error);
}

TEST(MapperOptions, InertialLocalBundleAdjustment) {
  EXPECT_FALSE(MapperProcessOptions::from_config(runtime::Config::empty(), {}).inertial.enabled);  // off by default
  const runtime::Config config = runtime::Config::parse(
      "imu: {enabled: true, window_keyframes: 7, estimate_gravity: false, init_min_keyframes: 8, wait_s: 2.5}\n",
      "inertial.yaml");
  const MapperProcessOptions options = MapperProcessOptions::from_config(config, {});
  EXPECT_TRUE(options.inertial.enabled);
  EXPECT_EQ(options.inertial.window_keyframes, 7);
  EXPECT_FALSE(options.inertial.estimate_gravity);
  EXPECT_EQ(options.inertial.init_min_keyframes, 8);
  EXPECT_EQ(options.inertial.wait_s, 2.5);
  EXPECT_FALSE(MapperProcessOptions::from_config(config, {"--imu", "none"}).inertial.enabled);
  EXPECT_TRUE(MapperProcessOptions::from_config(config, {"--imu", "auto"}).inertial.enabled);
  EXPECT_THROW(MapperProcessOptions::from_config(config, {"--imu", "maybe"}), std::runtime_error);
  const runtime::Config bad = runtime::Config::parse("imu: {window_keyframes: 0}\n", "inertial.yaml");
  try {
    MapperProcessOptions::from_config(bad, {});
    FAIL() << "expected a rejection";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("imu.window_keyframes"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace heslam::local_mapper
