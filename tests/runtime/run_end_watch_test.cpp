// RunEndRule: when a process watching a run from outside (a viewer started by hand) takes the run
// as ended, from the status samples it saw.
#include <gtest/gtest.h>

#include "runtime/run_end_watch.hpp"

namespace heslam::runtime {
namespace {

TEST(RunEndRule, TheSupervisorShuttingDownEndsTheRun) {
  RunEndRule rule;
  rule.observe("frontend", "/build/bin/heslam-frontend", false);
  rule.observe("supervisor", "/build/bin/heslam-supervisor", false);
  EXPECT_FALSE(rule.ended());
  rule.observe("frontend", "/build/bin/heslam-frontend", true);  // a component stopping is no run end
  EXPECT_FALSE(rule.ended());
  rule.observe("supervisor", "/build/bin/heslam-supervisor", true);
  ASSERT_TRUE(rule.ended());
  EXPECT_NE(rule.ended()->find("supervisor"), std::string::npos);
}

TEST(RunEndRule, OneHostsSupervisorOfARunOverSeveralHostsEndsItToo) {
  RunEndRule rule;
  rule.observe("supervisor@robot", "heslam-supervisor", true);
  ASSERT_TRUE(rule.ended());
  EXPECT_NE(rule.ended()->find("supervisor@robot"), std::string::npos);
}

TEST(RunEndRule, WithoutASupervisorTheReplayFinishingEndsTheRun) {
  RunEndRule rule;
  rule.observe("replay", "/usr/bin/heslam-replay", false);
  EXPECT_FALSE(rule.ended());
  rule.observe("replay", "/usr/bin/heslam-replay", true);
  ASSERT_TRUE(rule.ended());
  EXPECT_NE(rule.ended()->find("replay"), std::string::npos);
}

// Under a supervisor the mapper's final map comes after the replay's end: only the supervisor counts.
TEST(RunEndRule, UnderASupervisorTheReplayFinishingIsNotTheEnd) {
  RunEndRule rule;
  rule.observe("supervisor", "heslam-supervisor", false);
  rule.observe("replay", "heslam-replay", true);
  EXPECT_FALSE(rule.ended());
  rule.observe("supervisor", "heslam-supervisor", true);
  EXPECT_TRUE(rule.ended());
}

}  // namespace
}  // namespace heslam::runtime
