// tools/evaluate.sh end to end on a short synthetic pair written by heslam-synth: a KITTI-layout
// street (sequences/00 + poses/00.txt) and a EuRoC-layout room; both found, run in lockstep twice
// and once in real time, scored against their exact ground truth, tabled (CSV + Markdown) and plotted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
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
constexpr auto kEvaluateTimeout = 400s;
// Frames: enough to initialise and map a few keyframes, few enough for CI.
constexpr int kStreetFrames = 20;
constexpr int kRoomFrames = 30;

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::stringstream stream(line);
  for (std::string field; std::getline(stream, field, separator);) fields.push_back(field);
  if (!line.empty() && line.back() == separator) fields.emplace_back();
  return fields;
}

// CSV rows as maps column -> value.
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string header_line;
  std::getline(in, header_line);
  const auto header = split(header_line, ',');
  std::vector<std::map<std::string, std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    const auto fields = split(line, ',');
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < fields.size(); ++i) row[header[i]] = fields[i];
    rows.push_back(row);
  }
  return rows;
}

using test::run_to_end;

TEST(EvaluateScript, RunsSyntheticKittiAndEurocLayoutsEndToEnd) {
  test::ScratchDir dir("evaluate");
  const fs::path synth = test::bin_dir() / "heslam-synth";
  const fs::path kitti = dir.path() / "kitti";
  ASSERT_EQ(run_to_end(synth,
                       {"--preset", "street", "--format", "kitti", "--frames", std::to_string(kStreetFrames), "--out",
                        (kitti / "sequences/00").string()},
                       dir.path(), "synth_street", kSynthTimeout),
            0);
  // The KITTI odometry layout keeps the ground truth beside the sequences: poses/NN.txt.
  fs::create_directories(kitti / "poses");
  fs::rename(kitti / "sequences/00/poses.txt", kitti / "poses/00.txt");
  const fs::path euroc = dir.path() / "euroc";
  ASSERT_EQ(
      run_to_end(synth,
                 {"--preset", "room", "--frames", std::to_string(kRoomFrames), "--out", (euroc / "room").string()},
                 dir.path(), "synth_room", kSynthTimeout),
      0);

  const fs::path out = dir.path() / "out";
  std::string output;
  const int code = run_to_end("/bin/bash",
                              {(test::source_dir() / "tools/evaluate.sh").string(), "--kitti", kitti.string(),
                               "--euroc", euroc.string(), "--runs", "2", "--out", out.string(), "--domain",
                               std::to_string(test::exclusive_domain_id()), "--bin", test::bin_dir().string()},
                              dir.path(), "evaluate", kEvaluateTimeout, &output);
  ASSERT_EQ(code, 0) << output;

  const auto rows = read_csv(out / "results.csv");
  ASSERT_EQ(rows.size(), 2u) << read_file(out / "results.csv");
  for (const auto& row : rows) {
    const std::string& name = row.at("sequence");
    SCOPED_TRACE(name);
    const bool is_kitti = row.at("kind") == "kitti";
    EXPECT_EQ(name, is_kitti ? "kitti_00" : "room");
    EXPECT_EQ(row.at("frames"), std::to_string(is_kitti ? kStreetFrames : kRoomFrames));
    EXPECT_EQ(row.at("lockstep_identical"), "yes") << "lockstep runs must be bit-identical";
    const double ate_m = std::stod(row.at("ate_rmse_m"));
    // Exact synthetic ground truth: centimetres in the room, decimetres on 18 m of street at most.
    EXPECT_LT(ate_m, is_kitti ? 0.5 : 0.05);
    EXPECT_GE(ate_m, 0.0);
    EXPECT_NE(row.at("frame_ms_median"), "-");
    EXPECT_NE(row.at("frame_ms_p90"), "-");
    // Real time: a pose count, a dropped-frame count (machine speed decides how many) and an ATE.
    EXPECT_NE(row.at("tracked_realtime"), "-");
    EXPECT_NE(row.at("dropped_realtime"), "-");
    EXPECT_NE(row.at("ate_rmse_realtime_m"), "-");
    // A synthetic "sequences/00" is not KITTI 00: no paper number beside it.
    EXPECT_EQ(row.at("paper_he_slam_ate_m"), "");
    EXPECT_EQ(row.at("paper_orb_slam2_ate_m"), "");
    EXPECT_GT(fs::file_size(out / row.at("plot")), 1000u) << "trajectory plot";
    if (is_kitti) {
      EXPECT_NE(row.at("kitti_t_rel_pct"), "") << "KITTI drift column (- when shorter than 100 m)";
    }
  }
  // Progress: a line per sequence, per run as it starts and ends, the sequence's ATE (issue 39).
  EXPECT_NE(output.find("evaluate.sh: [1/2] kitti_00 (kitti, "), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh: [2/2] room (euroc, "), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh:   lockstep_2 (lockstep) ...\n"), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh:   lockstep_1 (lockstep): tracked " + std::to_string(kRoomFrames) + "/" +
                        std::to_string(kRoomFrames) + " in "),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("evaluate.sh:   realtime (realtime): tracked "), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh: [2/2] room: ATE lockstep "), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh: results in " + out.string() + " (results.md"), std::string::npos) << output;
  const std::string markdown = read_file(out / "results.md");
  EXPECT_NE(markdown.find("| kitti_00 | " + std::to_string(kStreetFrames) + " |"), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("paper HE-SLAM (m)"), std::string::npos);
}

// The paper's numbers go only beside the paper's sequences: KITTI by number and ground-truth frame
// count (the real 04 has 271 frames), EuRoC by the official folder name.
TEST(EvaluateScript, PaperNumbersOnlyForThePapersSequences) {
  const fs::path kitti_04 = test::shared_data() / "trajectories/kitti_gt_poses/04.txt";
  if (!fs::exists(kitti_04)) GTEST_SKIP() << "../shared/data/trajectories/kitti_gt_poses is absent";
  test::ScratchDir dir("evaluate_list");
  const fs::path kitti = dir.path() / "kitti";
  for (const std::string seq : {"04", "05"}) {
    fs::create_directories(kitti / "sequences" / seq / "image_0");
    fs::create_directories(kitti / "sequences" / seq / "image_1");
    std::ofstream(kitti / "sequences" / seq / "times.txt") << "0\n";
    std::ofstream(kitti / "sequences" / seq / "calib.txt") << "P0: 1\n";
  }
  fs::create_directories(kitti / "poses");
  fs::copy_file(kitti_04, kitti / "poses/04.txt");
  std::ofstream(kitti / "poses/05.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";  // not the real 05 (2761 frames)
  const fs::path euroc = dir.path() / "euroc";
  for (const std::string name : {"MH_01_easy", "my_flight"}) {
    for (const std::string cam : {"cam0", "cam1"}) {
      fs::create_directories(euroc / name / "mav0" / cam);
      std::ofstream(euroc / name / "mav0" / cam / "data.csv") << "#timestamp [ns],filename\n";
    }
  }
  std::string output;
  ASSERT_EQ(run_to_end("/bin/bash",
                       {(test::source_dir() / "tools/evaluate.sh").string(), "--kitti", kitti.string(), "--euroc",
                        euroc.string(), "--list"},
                       dir.path(), "evaluate_list", 30s, &output),
            0)
      << output;
  EXPECT_NE(output.find("kitti_04 " + (kitti / "sequences/04").string() + " gt=" + (kitti / "poses/04.txt").string() +
                        " paper_he_slam=0.233628 paper_orb_slam2=0.163535"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("paper_he_slam=0.0410544 paper_orb_slam2=0.0380801"), std::string::npos) << output;
  // Neither a 1-frame "05" nor an unknown EuRoC name gets one.
  EXPECT_NE(output.find("kitti_05 " + (kitti / "sequences/05").string() + " gt=" + (kitti / "poses/05.txt").string() +
                        " paper_he_slam=- paper_orb_slam2=-"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("my_flight " + (euroc / "my_flight").string() + " gt=none paper_he_slam=- paper_orb_slam2=-"),
            std::string::npos)
      << output;
}

TEST(EvaluateScript, NoSequenceIsOneLineAndExitOne) {
  test::ScratchDir dir("evaluate_empty");
  fs::create_directories(dir.path() / "empty");
  std::string output;
  const int code =
      run_to_end("/bin/bash",
                 {(test::source_dir() / "tools/evaluate.sh").string(), "--euroc", (dir.path() / "empty").string(),
                  "--out", (dir.path() / "out").string(), "--bin", test::bin_dir().string()},
                 dir.path(), "evaluate", 30s, &output);
  EXPECT_EQ(code, 1);
  EXPECT_NE(output.find("no sequence (expected DIR/mav0 or DIR/*/mav0"), std::string::npos) << output;
  EXPECT_EQ(
      run_to_end("/bin/bash", {(test::source_dir() / "tools/evaluate.sh").string(), "--runs", "0", "--euroc", "x"},
                 dir.path(), "evaluate_runs", 30s, &output),
      1);
  EXPECT_NE(output.find("--runs: expected a positive integer, got '0'"), std::string::npos) << output;
}

// Without --out the results go under ~/.cache/heslam (XDG_CACHE_HOME when set), never into the
// current folder (the source tree when run from there), and the script says where as it starts and
// ends. A stand-in heslam-supervisor that fails at once: what is tested is the script's own output.
TEST(EvaluateScript, DefaultOutIsUnderTheCacheAndSaidAloud) {
  test::ScratchDir dir("evaluate_default_out");
  const fs::path euroc = dir.path() / "euroc";
  for (const std::string cam : {"cam0", "cam1"}) {
    fs::create_directories(euroc / "flight" / "mav0" / cam);
    std::ofstream(euroc / "flight" / "mav0" / cam / "data.csv") << "#timestamp [ns],filename\n";
  }
  const fs::path bin = dir.path() / "bin";
  fs::create_directories(bin);
  for (const std::string tool : {"heslam-supervisor", "heslam-eval"}) {
    std::ofstream(bin / tool) << "#!/bin/sh\necho 'error: pipeline failed: a stand-in' >&2\nexit 1\n";
    fs::permissions(bin / tool, fs::perms::owner_all);
  }
  const fs::path cwd = dir.path() / "cwd";
  const fs::path home = dir.path() / "home";
  fs::create_directories(cwd);
  const std::string saved_home = std::getenv("HOME") != nullptr ? std::getenv("HOME") : "";
  const char* saved_cache = std::getenv("XDG_CACHE_HOME");
  const std::string saved_cache_value = saved_cache != nullptr ? saved_cache : "";
  setenv("HOME", home.c_str(), 1);
  unsetenv("XDG_CACHE_HOME");
  std::string output;
  // Run from `cwd`, as a user in the source tree would.
  const int code = run_to_end(
      "/bin/bash",
      {"-c", "cd \"$0\" && exec /bin/bash \"$@\"", cwd.string(), (test::source_dir() / "tools/evaluate.sh").string(),
       "--euroc", euroc.string(), "--no-realtime", "--bin", bin.string()},
      dir.path(), "evaluate_default_out", 60s, &output);
  setenv("HOME", saved_home.c_str(), 1);
  if (saved_cache != nullptr) setenv("XDG_CACHE_HOME", saved_cache_value.c_str(), 1);
  EXPECT_EQ(code, 1) << output;  // the stand-in's run failed
  EXPECT_NE(output.find("flight lockstep run failed: error: pipeline failed: a stand-in"), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh: [1/1] flight (euroc, "), std::string::npos) << output;
  EXPECT_NE(output.find("evaluate.sh:   lockstep_1 (lockstep) ..."), std::string::npos) << output;
  const std::string prefix = "results in " + (home / ".cache/heslam/evaluation-").string();
  const std::size_t said = output.find(prefix);
  ASSERT_NE(said, std::string::npos) << output;
  const fs::path out = output.substr(said + 11, prefix.size() - 11 + 15);  // + YYYYmmdd-HHMMSS
  EXPECT_TRUE(fs::exists(out / "results.csv")) << out;
  EXPECT_NE(output.find("evaluate.sh: results in " + out.string() + " (results.md"), std::string::npos) << output;
  EXPECT_TRUE(fs::is_empty(cwd)) << "nothing is written into the current folder";
}

}  // namespace
}  // namespace heslam
