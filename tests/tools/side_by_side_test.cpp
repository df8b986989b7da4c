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
fs::path fake_orbslam3(const fs::path& root, bool writes_stats) {
  fs::create_directories(root / "Examples/Stereo");
  fs::create_directories(root / "Vocabulary");
  std::ofstream(root / "Vocabulary/ORBvoc.txt") << "fake\n";
  std::ofstream(root / "Examples/Stereo/EuRoC.yaml") << "%YAML:1.0\n";
  const fs::path example = root / "Examples/Stereo/stereo_euroc";
  std::ofstream script(example);
  script << "#!/usr/bin/env bash\n"
         << "# args: vocabulary settings sequence times trajectory\n"
         << "set -e\n";
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
  void render_room() {
    ASSERT_EQ(run_to_end(test::bin_dir() / "heslam-synth",
                         {"--preset", "room", "--frames", std::to_string(kRoomFrames), "--out", room_.string()},
                         dir_.path(), "synth_room", kSynthTimeout),
              0);
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
  EXPECT_EQ(output, "side_by_side.sh: --orbslam3 DIR is required (an ORB-SLAM3 checkout built with REGISTER_TIMES)\n");

  const fs::path empty = dir_.path() / "empty";
  fs::create_directories(empty);
  EXPECT_EQ(side_by_side({"--orbslam3", empty.string(), room_.string(), (dir_.path() / "out").string()}, &output), 2);
  EXPECT_EQ(output, "side_by_side.sh: no ORB-SLAM3 stereo example at " + empty.string() +
                        "/Examples/Stereo/stereo_euroc (build ORB-SLAM3 first: its build.sh)\n");

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
