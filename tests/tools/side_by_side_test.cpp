// tools/bench/side_by_side.sh on a synthetic EuRoC room: a stand-in for the user's ORB-SLAM3 build (a
// script at Examples/Stereo/stereo_euroc writing ORB-SLAM3's TrackingTimeStats.txt with known per-frame
// times and a frame trajectory) against heslam's real real-time pipeline, in one table; and the lines
// it gives when ORB-SLAM3 is missing or was built without REGISTER_TIMES.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Bounds of a hung script, not performance assertions.
constexpr auto kSynthTimeout = 120s;
constexpr auto kScriptTimeout = 300s;
constexpr int kRoomFrames = 30;

using test::run_to_end;

// An ORB-SLAM3 checkout as the script expects it. With stats, its stereo_euroc writes Total[ms] = 1, 2,
// ..., one row per frame of the times file (median 15.5 ms, p90 27 ms for 30 frames), and the frame
// trajectory from the ground truth (EuRoC-format stamps in ns).
// inertial: the stereo-inertial example instead (Examples/Stereo-Inertial/stereo_inertial_euroc), which
// also reads mav0/imu0/data.csv (it fails without one) and writes body poses (the ground truth's).
fs::path fake_orbslam3(const fs::path& root, bool writes_stats, bool inertial = false) {
  const std::string examples = inertial ? "Examples/Stereo-Inertial" : "Examples/Stereo";
  fs::create_directories(root / examples);
  fs::create_directories(root / "Vocabulary");
  std::ofstream(root / "Vocabulary/ORBvoc.txt") << "fake\n";
  std::ofstream(root / examples / "EuRoC.yaml") << "%YAML:1.0\n";
  const fs::path example = root / examples / (inertial ? "stereo_inertial_euroc" : "stereo_euroc");
  std::ofstream script(example);
  script << "#!/usr/bin/env bash\n"
         << "# args: vocabulary settings sequence times trajectory\n"
         << "set -e\n";
  if (inertial) script << "test -s \"$3/mav0/imu0/data.csv\"\n";
  if (writes_stats) {
    script << "echo '#Image Rect[ms], Image Resize[ms], ORB ext[ms], Stereo match[ms], IMU preint[ms], "
              "Pose pred[ms], LM track[ms], KF dec[ms], Total[ms]' > TrackingTimeStats.txt\n"
           << "awk '{ printf \"0,0,0,0,0,0,0,0,%d.000000\\n\", NR }' \"$4\" >> TrackingTimeStats.txt\n"
           << "awk -F, '!/^#/ { print $1, $2, $3, $4, $6, $7, $8, $5 }' "
              "\"$3/mav0/state_groundtruth_estimate0/data.csv\" > \"$5_frames.txt\"\n";
  }
  script << "exit 0\n";
  script.close();
  fs::permissions(example, fs::perms::owner_all, fs::perm_options::add);
  return root;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; stream >> field;) fields.push_back(field);
  return fields;
}

class SideBySideScript : public ::testing::Test {
 protected:
  void render_room(bool imu = false) {
    std::vector<std::string> args{"--preset", "room", "--frames", std::to_string(kRoomFrames), "--out", room_.string()};
    if (imu) args.push_back("--imu");
    ASSERT_EQ(run_to_end(test::bin_dir() / "heslam-synth", args, dir_.path(), "synth_room", kSynthTimeout), 0);
  }

  // The frame list alone: enough for every check that ends before a pipeline runs.
  void frame_list_only() {
    fs::create_directories(room_ / "mav0/cam0");
    std::ofstream(room_ / "mav0/cam0/data.csv")
        << "#timestamp [ns],filename\n1600000000000000000,1600000000000000000.png\n";
  }

  int side_by_side(const std::vector<std::string>& args, std::string* output) {
    std::vector<std::string> full{(test::source_dir() / "tools/bench/side_by_side.sh").string()};
    full.insert(full.end(), args.begin(), args.end());
    return run_to_end("/bin/bash", full, dir_.path(), "side_by_side", kScriptTimeout, output);
  }

  test::ScratchDir dir_{"side_by_side"};
  fs::path room_ = dir_.path() / "room";
};

// Both tables: stereo (stereo_euroc beside euroc_realtime.yaml) and --inertial (stereo_inertial_euroc
// beside euroc_inertial_realtime.yaml on a room rendered with --imu).
void expect_table(const std::string& output);

TEST_F(SideBySideScript, TablesBothSystemsPerRoundWithTheirPerFrameTimes) {
  render_room();
  const fs::path orbslam3 = fake_orbslam3(dir_.path() / "ORB_SLAM3", true);
  const fs::path out = dir_.path() / "out";
  std::string output;
  ::setenv("HESLAM_BUILD_DIR", test::bin_dir().parent_path().string().c_str(), 1);
  ASSERT_EQ(side_by_side({"--orbslam3", orbslam3.string(), "--rounds", "1", "--domain",
                          std::to_string(test::exclusive_domain_id()), room_.string(), out.string()},
                         &output),
            0)
      << output;
  expect_table(output);
}

TEST_F(SideBySideScript, InertialTablesTheStereoInertialExampleBesideHeslamsInertialPipeline) {
  render_room(/*imu=*/true);
  const fs::path orbslam3 = fake_orbslam3(dir_.path() / "ORB_SLAM3", true, /*inertial=*/true);
  const fs::path out = dir_.path() / "out";
  std::string output;
  ::setenv("HESLAM_BUILD_DIR", test::bin_dir().parent_path().string().c_str(), 1);
  ASSERT_EQ(side_by_side({"--orbslam3", orbslam3.string(), "--inertial", "--rounds", "1", "--domain",
                          std::to_string(test::exclusive_domain_id()), room_.string(), out.string()},
                         &output),
            0)
      << output;
  EXPECT_NE(output.find("stereo-inertial, ORB-SLAM3 " + orbslam3.string() + " (EuRoC.yaml)"), std::string::npos)
      << output;
  EXPECT_NE(fs::file_size(out / "times.txt"), 0u);  // the frame-stamps file ORB-SLAM3 reads, written by the script
  expect_table(output);
  // The fake wrote the ground truth's body poses: ORB-SLAM3's inertial trajectory is compared as body poses.
  for (const auto& line : lines_of(output)) {
    const auto fields = fields_of(line);
    if (fields.size() == 6 && fields[1] == "ORB-SLAM3") {
      EXPECT_LT(std::stod(fields[5]), 0.01) << line;
    }
  }
}

void expect_table(const std::string& output) {
  bool orbslam3_row = false, heslam_row = false, ratio = false;
  for (const auto& line : lines_of(output)) {
    const auto fields = fields_of(line);
    if (fields.size() == 6 && fields[0] == "1" && fields[1] == "ORB-SLAM3") {
      orbslam3_row = true;
      EXPECT_EQ(fields[2], std::to_string(kRoomFrames)) << line;
      EXPECT_EQ(fields[3], "15.50") << line;
      EXPECT_EQ(fields[4], "27.00") << line;
      EXPECT_NE(fields[5], "-") << "ATE against the room's ground truth: " << line;
    }
    if (fields.size() == 6 && fields[0] == "1" && fields[1] == "heslam") {
      heslam_row = true;
      // Real time: the frames with a pose depend on the machine's speed; the per-frame time is a number.
      EXPECT_GT(std::stoi(fields[2]), 0) << line;
      EXPECT_LE(std::stoi(fields[2]), kRoomFrames) << line;
      EXPECT_GT(std::stod(fields[3]), 0.0) << line;
      EXPECT_NE(fields[5], "-") << line;
    }
    ratio = ratio || line.rfind("round 1: heslam / ORB-SLAM3 median per frame = ", 0) == 0;
  }
  EXPECT_TRUE(orbslam3_row) << output;
  EXPECT_TRUE(heslam_row) << output;
  EXPECT_TRUE(ratio) << output;
}

TEST_F(SideBySideScript, SaysWhatIsMissingInOneLine) {
  frame_list_only();
  std::string output;
  EXPECT_EQ(side_by_side({room_.string(), (dir_.path() / "out").string()}, &output), 2);
  const std::string required =
      "side_by_side.sh: ORB-SLAM3 is missing: --orbslam3 DIR is required (an ORB-SLAM3 checkout built with its "
      "build.sh and REGISTER_TIMES; heslam does not ship or build it: docs/imu.md, Running ORB-SLAM3 beside heslam)\n";
  EXPECT_EQ(output, required);
  EXPECT_EQ(side_by_side({"--inertial", room_.string(), (dir_.path() / "out").string()}, &output), 2);
  EXPECT_EQ(output, required);

  const fs::path empty = dir_.path() / "empty";
  fs::create_directories(empty);
  EXPECT_EQ(side_by_side({"--orbslam3", empty.string(), room_.string(), (dir_.path() / "out").string()}, &output), 2);
  EXPECT_EQ(output, "side_by_side.sh: ORB-SLAM3 is missing: no stereo_euroc at " + empty.string() +
                        "/Examples/Stereo/stereo_euroc (build ORB-SLAM3 first: its build.sh)\n");
  EXPECT_EQ(side_by_side({"--orbslam3", empty.string(), "--inertial", room_.string(), (dir_.path() / "out").string()},
                         &output),
            2);
  EXPECT_EQ(output, "side_by_side.sh: ORB-SLAM3 is missing: no stereo_inertial_euroc at " + empty.string() +
                        "/Examples/Stereo-Inertial/stereo_inertial_euroc (build ORB-SLAM3 first: its build.sh)\n");
  // --inertial on a folder without imu0/: the ORB-SLAM3 example is there, the IMU is not.
  const fs::path inertial = fake_orbslam3(dir_.path() / "ORB_SLAM3_inertial", true, /*inertial=*/true);
  EXPECT_EQ(
      side_by_side({"--orbslam3", inertial.string(), "--inertial", room_.string(), (dir_.path() / "out").string()},
                   &output),
      2);
  EXPECT_EQ(output, "side_by_side.sh: " + (room_ / "mav0/imu0/data.csv").string() +
                        ": missing (--inertial needs the IMU: EuRoC's imu0/)\n");

  const fs::path no_stats = fake_orbslam3(dir_.path() / "ORB_SLAM3_plain", false);
  EXPECT_EQ(side_by_side({"--orbslam3", no_stats.string(), room_.string(), (dir_.path() / "out2").string()}, &output),
            1);
  EXPECT_NE(output.find("side_by_side.sh: ORB-SLAM3 wrote no " + (dir_.path() / "out2").string() +
                        "/orbslam3_1/TrackingTimeStats.txt: build it with REGISTER_TIMES defined"),
            std::string::npos)
      << output;
}

}  // namespace
}  // namespace heslam
