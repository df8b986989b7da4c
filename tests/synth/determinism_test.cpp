// Same seed, same bytes (in memory and through the CLI); another seed, other images.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "synth_test_util.hpp"
#include "tools/synth/sequence.hpp"

namespace heslam::synth {
namespace {

bool same_bytes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

// Element-wise, in plain loops (Eigen's vectorized isApprox trips a GCC 12 AVX-512 false warning).
double max_abs_diff(const Pose3& a, const Pose3& b) {
  double d = 0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  return d;
}

TEST(SynthDeterminism, SameSeedGivesIdenticalImagesAndOtherSeedDiffers) {
  const Preset preset = test::repo_preset("room");
  const SynthSequence a = render(preset, {.seed = 5, .frames = 2});
  const SynthSequence b = render(preset, {.seed = 5, .frames = 2, .threads = 2});
  const SynthSequence c = render(preset, {.seed = 6, .frames = 2});
  for (int i = 0; i < 2; ++i) {
    EXPECT_TRUE(same_bytes(a.frames[i].left, b.frames[i].left)) << i;
    EXPECT_TRUE(same_bytes(a.frames[i].right, b.frames[i].right)) << i;
    EXPECT_EQ(max_abs_diff(a.frames[i].T_wc_left, b.frames[i].T_wc_left), 0.0);
    EXPECT_FALSE(same_bytes(a.frames[i].left, c.frames[i].left)) << i;
    EXPECT_GT(max_abs_diff(a.frames[i].T_wc_left, c.frames[i].T_wc_left), 1e-6) << "seed moves the trajectory";
  }
}

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(SynthDeterminism, CliWritesIdenticalFilesForOneSeed) {
  namespace fs = std::filesystem;
  const fs::path base = fs::temp_directory_path() / "heslam_synth_cli_test";
  fs::remove_all(base);
  const std::string exe = (::heslam::test::bin_dir() / "heslam-synth").string();
  for (const char* run : {"a", "b"}) {
    const std::string cmd = exe + " --preset room --frames 2 --seed 9 --out " + (base / run).string() + " 2>/dev/null";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(base / "a")) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), base / "a");
    ASSERT_TRUE(fs::exists(base / "b" / rel)) << rel;
    // synth.yaml names the preset file, not the output folder, so every file must match.
    EXPECT_EQ(file_bytes(entry.path()), file_bytes(base / "b" / rel)) << rel;
    ++files;
  }
  EXPECT_EQ(files, 13);  // 4 PNGs, 2 data.csv, 2 sensor.yaml, body, gt, timestamps, synth, settings
  fs::remove_all(base);
}

// --list: a line per preset with its cost and purpose, not bare names (issue 39).
TEST(SynthDeterminism, CliListsEachPresetWithItsLengthDurationAndPurpose) {
  const auto out = std::filesystem::temp_directory_path() / "heslam_synth_list.txt";
  const std::string exe = (::heslam::test::bin_dir() / "heslam-synth").string();
  ASSERT_EQ(std::system((exe + " --list >" + out.string()).c_str()), 0);
  const std::string text = file_bytes(out);
  std::filesystem::remove(out);
  const Preset room = load_preset(find_preset("room"));
  const std::string room_line = "room             600 frames,   30.0 s at 20 Hz, ";
  ASSERT_NE(text.find(room_line), std::string::npos) << text;
  EXPECT_NE(text.find(" m travelled: " + room.purpose + "\n", text.find(room_line)), std::string::npos) << text;
  std::size_t lines = 0;
  for (const char c : text) lines += c == '\n' ? 1 : 0;
  EXPECT_EQ(lines, known_presets().size()) << text;
  EXPECT_EQ(text.find("(no purpose: field)"), std::string::npos) << text;
}

TEST(SynthDeterminism, CliRejectsUnknownPresetWithOneClearLine) {
  const std::string exe = (::heslam::test::bin_dir() / "heslam-synth").string();
  const auto out = std::filesystem::temp_directory_path() / "heslam_synth_bad_preset.txt";
  const auto never = std::filesystem::temp_directory_path() / "heslam_synth_cli_never";
  std::filesystem::remove_all(never);
  const std::string cmd = exe + " --preset no_such_scene --out " + never.string() + " 2>" + out.string();
  EXPECT_NE(std::system(cmd.c_str()), 0);
  const std::string text = file_bytes(out);
  EXPECT_NE(text.find("heslam-synth: unknown preset 'no_such_scene'"), std::string::npos) << text;
  EXPECT_NE(text.find("room"), std::string::npos) << "lists the known presets: " << text;
  EXPECT_FALSE(std::filesystem::exists(never)) << "nothing is written for a bad preset";
  std::filesystem::remove(out);
}

}  // namespace
}  // namespace heslam::synth
