// heslam-synth's progress: a live line on a terminal, a line per 10 % in a log, nothing with --quiet;
// the CLI with stderr in a file (not a terminal) writes plain lines without carriage returns.
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

#include <gtest/gtest.h>

#include "test_support.hpp"
#include "tools/synth/progress_report.hpp"

namespace heslam::synth {
namespace {

std::size_t count(const std::string& text, char c) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), c));
}

TEST(SynthProgress, NotATerminalPrintsOneLinePerTenPercent) {
  std::ostringstream out;
  ProgressReport report(out, ProgressReport::mode_for(false, false), "room");
  for (int done = 1; done <= 120; ++done) report.update(done, 120, 0.5 * done);
  const std::string text = out.str();
  EXPECT_EQ(count(text, '\r'), 0u) << text;
  EXPECT_EQ(count(text, '\n'), 10u) << text;
  EXPECT_EQ(text.rfind("heslam-synth: room 12/120 frames  10% (2.0 pairs/s)\n", 0), 0u) << text;
  EXPECT_NE(text.find("heslam-synth: room 120/120 frames 100% (2.0 pairs/s)\n"), std::string::npos) << text;
}

TEST(SynthProgress, ShortRunsPrintEveryFrameOnceAndTheLastAlways) {
  std::ostringstream out;
  ProgressReport report(out, ProgressReport::Mode::steps, "room");
  for (int done = 1; done <= 3; ++done) report.update(done, 3, 1.0);
  EXPECT_EQ(count(out.str(), '\n'), 3u) << out.str();
}

TEST(SynthProgress, TerminalRedrawsAtMostTenTimesASecondAndEndsTheLine) {
  std::ostringstream out;
  ProgressReport report(out, ProgressReport::mode_for(false, true), "room");
  // 100 frames in 1 s: 10 redraws by the clock plus the final one.
  for (int done = 1; done <= 100; ++done) report.update(done, 100, 0.01 * done);
  const std::string text = out.str();
  EXPECT_GE(count(text, '\r'), 10u) << text;
  EXPECT_LE(count(text, '\r'), 11u) << text;
  EXPECT_EQ(count(text, '\n'), 1u);
  EXPECT_EQ(text.back(), '\n');
}

TEST(SynthProgress, QuietPrintsNothing) {
  std::ostringstream out;
  ProgressReport report(out, ProgressReport::mode_for(true, true), "room");
  for (int done = 1; done <= 10; ++done) report.update(done, 10, 1.0);
  EXPECT_TRUE(out.str().empty());
}

std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(SynthProgress, CliLogFileGetsPlainLinesAndQuietNone) {
  const test::ScratchDir scratch("synth_progress");
  const auto& dir = scratch.path();
  const std::string exe = (test::bin_dir() / "heslam-synth").string();
  const std::string run = exe + " --preset room --frames 3 --seed 1 --no-events --out " + (dir / "out").string();
  ASSERT_EQ(std::system((run + " 2>" + (dir / "log.txt").string()).c_str()), 0);
  const std::string log = file_text(dir / "log.txt");
  EXPECT_EQ(count(log, '\r'), 0u) << log;
  EXPECT_EQ(count(log, '\n'), 4u) << "3 progress lines and the summary:\n" << log;
  EXPECT_NE(log.find("room 3/3 frames 100%"), std::string::npos) << log;
  ASSERT_EQ(std::system((run + " --quiet 2>" + (dir / "quiet.txt").string()).c_str()), 0);
  EXPECT_EQ(file_text(dir / "quiet.txt"), "");
}

}  // namespace
}  // namespace heslam::synth
