// The run's verdict from the programs' final counters (runtime/supervisor/run_verdict.hpp) and the
// quoting of users' values in one-line errors (runtime/quote_value.hpp): no processes.
#include <gtest/gtest.h>

#include <string>

#include "runtime/quote_value.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/supervisor/run_verdict.hpp"

namespace heslam::supervisor {
namespace {

ProgramReport recorder(std::uint64_t recorded, std::uint64_t with_pose, std::uint64_t accounted) {
  return {"recorder",
          {{runtime::kFramesRecorded, recorded},
           {runtime::kFramesWithPose, with_pose},
           {runtime::kFramesAccounted, accounted}},
          "tracked " + std::to_string(with_pose) + "/" + std::to_string(accounted) + " frames, " +
              std::to_string(accounted - with_pose) + " lost, trajectory /tmp/t.txt"};
}

ProgramReport frontend(std::uint64_t odometry_frames) {
  return {"frontend", {{runtime::kOdometryFrames, odometry_frames}}, ""};
}

ProgramReport replay(std::uint64_t published, std::uint64_t total, std::uint64_t skipped) {
  return {"replay",
          {{runtime::kFramesPublished, published}, {runtime::kFramesTotal, total}, {runtime::kImagesSkipped, skipped}},
          std::to_string(published) + " of " + std::to_string(total) + " frames published" +
              (skipped > 0 ? ", " + std::to_string(skipped) + " skipped (a missing or corrupt image)" : "")};
}

// A forger that copied the run id published odometry next to the frontend; the
// recorder counted the conflict. Before, the run ended with exit code 0 and "tracked 160/160 frames".
TEST(RunVerdict, TwoLiveWritersOfOneRoleFailTheRunNamingTheTopic) {
  ProgramReport seen = recorder(160, 160, 160);
  seen.counters[runtime::kWriterConflicts] = 1;
  seen.counters[std::string(runtime::kWriterConflictsOn) + "heslam/odometry"] = 1;
  const RunVerdict verdict = judge_run({seen, frontend(160), replay(160, 160, 0)});
  ASSERT_TRUE(verdict.failure);
  EXPECT_EQ(*verdict.failure,
            "recorder: two live writers claimed one role on heslam/odometry (1 conflict: a forged participant or a "
            "second copy of a component; its log names both writers)");
  EXPECT_TRUE(verdict.writer_conflict);
  EXPECT_FALSE(judge_run({recorder(160, 160, 160), frontend(160), replay(160, 160, 0)}).failure);
}

// A recorder stalled until the frontend had gone: 40 frames recorded, 160 produced. Before, the run
// ended with exit code 0 and "tracked 40/40 frames, 0 lost".
TEST(RunVerdict, FramesTheFrontendProducedButTheOutputLacksFailTheRun) {
  const RunVerdict verdict = judge_run({recorder(40, 40, 40), frontend(160), replay(160, 160, 0)});
  ASSERT_TRUE(verdict.failure);
  EXPECT_EQ(*verdict.failure,
            "recorder: 120 of the 160 frames the frontend produced odometry for are missing from its output (it "
            "recorded 40; it was stalled or cut off while they were published)");
  // The recorder's own count (40/40) is restated against what the replay published.
  EXPECT_EQ(verdict.results, "tracked 40/160 frames, 120 lost, trajectory /tmp/t.txt; 160 of 160 frames published");
}

TEST(RunVerdict, ACompleteRunPassesWithTheResultsJoined) {
  const RunVerdict verdict = judge_run({recorder(160, 158, 160), frontend(160), replay(160, 160, 0)});
  EXPECT_FALSE(verdict.failure);
  EXPECT_EQ(verdict.results, "tracked 158/160 frames, 2 lost, trajectory /tmp/t.txt; 160 of 160 frames published");
}

// Real time: frames the frontend missed have no odometry; only what it produced must be recorded.
TEST(RunVerdict, FramesTheFrontendMissedAreNotMissingFromTheOutput) {
  const RunVerdict verdict = judge_run({recorder(145, 145, 160), frontend(145), replay(160, 160, 0)});
  EXPECT_FALSE(verdict.failure);
}

// The last line says what the replay skipped, not just "159/159".
TEST(RunVerdict, ASkippedPairIsOnTheLastLine) {
  const RunVerdict verdict = judge_run({recorder(159, 159, 159), frontend(159), replay(159, 160, 1)});
  EXPECT_FALSE(verdict.failure);
  EXPECT_EQ(verdict.results,
            "tracked 159/159 frames, 0 lost, trajectory /tmp/t.txt; 159 of 160 frames published, 1 "
            "skipped (a missing or corrupt image)");
}

// A test harness's timeout (or a user's Ctrl-C) stopped a 720-frame replay at frame 601; everything
// stopped cleanly. Before, the run ended with exit code 0 and a trajectory of 601 poses.
TEST(RunVerdict, ARecordingStoppedBeforeItsEndFailsTheRun) {
  ProgramReport cut = replay(601, 720, 0);
  cut.counters[runtime::kFramesNotPlayed] = 119;
  const RunVerdict verdict = judge_run({recorder(601, 601, 601), frontend(601), cut});
  ASSERT_TRUE(verdict.failure);
  EXPECT_EQ(*verdict.failure,
            "replay was stopped before the end of its input (119 of its 720 frames not played): the outputs hold "
            "only the run's beginning");
  EXPECT_FALSE(verdict.writer_conflict);
  // Every frame played (or a looping replay, which counts none): no verdict.
  cut.counters[runtime::kFramesNotPlayed] = 0;
  EXPECT_FALSE(judge_run({recorder(601, 601, 601), frontend(601), cut}).failure);
}

// Programs that report none of these counters (a talker, a pipeline without recorder) are judged by
// their exit codes alone.
TEST(RunVerdict, WithoutTheCountersOnlyTheResultsAreJoined) {
  const RunVerdict verdict = judge_run({{"a", {}, "done"}, {"b", {}, ""}, {"c", {}, "ok"}});
  EXPECT_FALSE(verdict.failure);
  EXPECT_EQ(verdict.results, "done; ok");
}

TEST(QuoteValue, AHugeValueIsCutAndItsSizeSaid) {
  const std::string huge(10 * 1024 * 1024, 'x');
  EXPECT_EQ(runtime::quote_value(huge), std::string(80, 'x') + "... (10485760 bytes)");
  EXPECT_EQ(runtime::quote_value("short"), "short");
}

TEST(QuoteValue, BytesThatAreNotPrintableUtf8AreEscaped) {
  EXPECT_EQ(runtime::quote_value("a\xFF"
                                 "b"),
            "a\\xFFb");
  EXPECT_EQ(runtime::quote_value("line\nbreak\x1b[2J"), "line\\x0Abreak\\x1B[2J");
  EXPECT_EQ(runtime::quote_value("caf\xC3\xA9"), "caf\xC3\xA9");  // valid UTF-8 stays
  EXPECT_EQ(runtime::quote_value("\xC3"), "\\xC3");               // a cut sequence does not
}

}  // namespace
}  // namespace heslam::supervisor
