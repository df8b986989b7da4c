// The supervisor's run progress line (runtime/supervisor/run_progress.hpp) and the $(stem NAME)
// substitution that names a run's outputs: DDS-free, no process started.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "runtime/supervisor/pipeline.hpp"
#include "runtime/supervisor/run_progress.hpp"

namespace heslam::supervisor {
namespace {

using Clock = RunProgress::Clock;

RunCounts counts(std::uint64_t tracked, std::uint64_t published, std::uint64_t total, double fps) {
  RunCounts c;
  c.tracked = tracked;
  c.published = published;
  c.total = total;
  c.fps = fps;
  return c;
}

// The percent says what it counts: published frames; tracked frames (with a pose) stand apart.
TEST(RunProgress, LineShowsPublishedOfTotalPercentTrackedFpsAndEta) {
  EXPECT_EQ(format_run_progress(counts(40, 42, 160, 20.0)),
            "published 42/160 frames   26%, 40 tracked  20.0 fps  ETA 5.9 s");
  RunCounts no_recorder = counts(0, 42, 160, 0.0);
  no_recorder.tracked.reset();
  EXPECT_EQ(format_run_progress(no_recorder), "published 42/160 frames   26%  0.0 fps  ETA -");
  // A live camera: no total.
  EXPECT_EQ(format_run_progress(counts(7, 8, 0, 10.0)), "published 8 frames, 7 tracked  10.0 fps");
}

TEST(RunProgress, TrackedCountIsReadFromTheRecordersStatusMessage) {
  EXPECT_EQ(tracked_from_message("tracked 158/160 frames, 2 lost, trajectory /tmp/x.txt"), 158u);
  EXPECT_FALSE(tracked_from_message("published 95 frames").has_value());
  EXPECT_FALSE(tracked_from_message("tracked everything").has_value());
  EXPECT_FALSE(tracked_from_message("").has_value());
}

// Not a terminal (a log, a pipe, CI): one plain line per 10 % of the frames however often the status
// comes, none before the first 10 % or without a total; a step jumped over is not printed twice.
TEST(RunProgress, PlainModePrintsOneLinePerTenPercent) {
  RunProgress progress(RunProgress::Mode::kPlain);
  const Clock::time_point t0 = Clock::now();
  std::vector<std::string> lines;
  for (std::uint64_t published = 0; published <= 160; published += 4) {
    if (auto line = progress.update(counts(published, published, 160, 20.0), t0)) lines.push_back(*line);
  }
  ASSERT_EQ(lines.size(), 10u);
  EXPECT_EQ(lines.front(), "published 16/160 frames   10%, 16 tracked  20.0 fps  ETA 7.2 s");
  EXPECT_EQ(lines.back(), "published 160/160 frames  100%, 160 tracked  20.0 fps  ETA 0.0 s");

  RunProgress jumpy(RunProgress::Mode::kPlain);
  EXPECT_TRUE(jumpy.update(counts(70, 70, 100, 1.0), t0).has_value());  // 70 %: one line, not seven
  EXPECT_FALSE(jumpy.update(counts(75, 75, 100, 1.0), t0).has_value());
  EXPECT_TRUE(jumpy.update(counts(80, 80, 100, 1.0), t0).has_value());

  RunProgress unknown_total(RunProgress::Mode::kPlain);
  EXPECT_FALSE(unknown_total.update(counts(50, 50, 0, 1.0), t0).has_value());
  RunProgress off(RunProgress::Mode::kOff);
  EXPECT_FALSE(off.update(counts(50, 50, 100, 1.0), t0).has_value());
}

// A terminal: the current line when it changed, at most ten times a second.
TEST(RunProgress, LiveModeRedrawsChangesAtMostTenTimesASecond) {
  RunProgress progress(RunProgress::Mode::kLive);
  const Clock::time_point t0 = Clock::now();
  EXPECT_FALSE(progress.update(counts(0, 0, 160, 0.0), t0).has_value());  // nothing published yet
  EXPECT_TRUE(progress.update(counts(1, 1, 160, 0.0), t0).has_value());
  EXPECT_FALSE(progress.update(counts(2, 2, 160, 0.0), t0 + std::chrono::milliseconds(50)).has_value());
  EXPECT_TRUE(progress.update(counts(2, 2, 160, 0.0), t0 + std::chrono::milliseconds(150)).has_value());
  EXPECT_FALSE(progress.update(counts(2, 2, 160, 0.0), t0 + std::chrono::milliseconds(400)).has_value());  // unchanged
}

// One naming scheme for a run's outputs: OUTPUT stem + .map / .loop / .viewer beside OUTPUT.
TEST(PipelineArgs, StemIsTheValueWithoutItsExtension) {
  const std::map<std::string, std::string> args{{"output", "/runs/mh01.txt"}, {"plain", "/runs/mh01"}};
  std::vector<std::string> unknown;
  EXPECT_EQ(substitute_args("$(stem output).map", args, unknown), "/runs/mh01.map");
  EXPECT_EQ(substitute_args("$(arg output)", args, unknown), "/runs/mh01.txt");
  EXPECT_EQ(substitute_args("$(stem plain).loop", args, unknown), "/runs/mh01.loop");
  EXPECT_TRUE(unknown.empty());
  EXPECT_EQ(substitute_args("$(stem nope).map", args, unknown), ".map");
  EXPECT_EQ(unknown, std::vector<std::string>{"nope"});
}

}  // namespace
}  // namespace heslam::supervisor
