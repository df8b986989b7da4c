// Stats: counters and nearest-rank percentiles over a sliding window, on known values.
#include "runtime/stats.hpp"

#include <gtest/gtest.h>

namespace heslam::runtime {
namespace {

TEST(Stats, PercentilesOfKnownValues) {
  Stats stats;
  for (int i = 1; i <= 100; ++i) stats.record_ms("extract", i);
  const auto stages = stats.stages();
  ASSERT_EQ(stages.size(), 1u);
  EXPECT_EQ(stages[0].name, "extract");
  EXPECT_EQ(stages[0].count, 100u);
  EXPECT_DOUBLE_EQ(stages[0].p50_ms, 50);
  EXPECT_DOUBLE_EQ(stages[0].p90_ms, 90);
  EXPECT_DOUBLE_EQ(stages[0].p99_ms, 99);
  EXPECT_DOUBLE_EQ(stages[0].max_ms, 100);
}

TEST(Stats, WindowKeepsOnlyRecentValues) {
  Stats stats(10);
  for (int i = 0; i < 10; ++i) stats.record_ms("s", 1000);
  for (int i = 1; i <= 10; ++i) stats.record_ms("s", i);
  const auto stage = stats.stages().at(0);
  EXPECT_EQ(stage.count, 10u);
  EXPECT_DOUBLE_EQ(stage.max_ms, 10);
  EXPECT_DOUBLE_EQ(stage.p50_ms, 5);
}

TEST(Stats, CountersAccumulate) {
  Stats stats;
  stats.count("frames");
  stats.count("frames", 4);
  stats.count("dropped");
  EXPECT_EQ(stats.counters(), (std::map<std::string, uint64_t>{{"dropped", 1}, {"frames", 5}}));
}

}  // namespace
}  // namespace heslam::runtime
