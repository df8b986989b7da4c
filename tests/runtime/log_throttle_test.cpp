// LogThrottle: a burst, then one line per period with the count of what it stands for; classes are
// independent; a quiet class starts a new burst; flush reports what is held back. Clock injected.
#include "runtime/log_throttle.hpp"

#include <gtest/gtest.h>

namespace heslam::runtime {
namespace {

constexpr std::int64_t kMs = 1'000'000;

struct FakeClock {
  std::int64_t now_ns = 0;
  LogThrottle::NowNs function() {
    return [this] { return now_ns; };
  }
};

// 160 identical per-frame warnings at 20 Hz (8 s), as a replay of a bad recording produces them.
TEST(LogThrottle, RepeatedWarningsBecomeABurstAndOneLinePerSecond) {
  FakeClock clock;
  LogThrottle throttle({.burst = 3, .period_ns = 1000 * kMs}, clock.function());
  std::vector<std::string> printed;
  for (int frame = 0; frame < 160; ++frame) {
    clock.now_ns = frame * 50 * kMs;
    if (auto line = throttle.admit("bad_frames", "frame " + std::to_string(frame) + ": left image is 640x480")) {
      printed.push_back(*line);
    }
  }
  ASSERT_GE(printed.size(), 3u);
  EXPECT_EQ(printed[0], "frame 0: left image is 640x480");
  EXPECT_EQ(printed[1], "frame 1: left image is 640x480");
  EXPECT_EQ(printed[2], "frame 2: left image is 640x480 (further 'bad_frames' warnings: one line per 1 s)");
  // Frame 2 printed at 100 ms; frames 3..22 are held back until 1 s has passed (frame 22 at 1.1 s).
  ASSERT_GE(printed.size(), 4u);
  EXPECT_EQ(printed[3], "frame 22: left image is 640x480 (repeated 20 times in 1.0 s)");
  EXPECT_EQ(printed[4], "frame 42: left image is 640x480 (repeated 20 times in 1.0 s)");
  // 3 + one per second over the remaining 7.85 s.
  EXPECT_EQ(printed.size(), 3u + 7u);
  // Every occurrence is accounted for: printed, or counted in a "repeated" line, or still held back.
  std::size_t counted = 3;
  for (std::size_t i = 3; i < printed.size(); ++i) {
    const auto at = printed[i].find("(repeated ");
    ASSERT_NE(at, std::string::npos) << printed[i];
    counted += std::stoul(printed[i].substr(at + 10));
  }
  clock.now_ns += 10 * kMs;
  const auto rest = throttle.flush();
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0].rfind("frame 159: left image is 640x480 (repeated ", 0), 0u) << rest[0];
  counted += std::stoul(rest[0].substr(rest[0].find("(repeated ") + 10));
  EXPECT_EQ(counted, 160u);
  EXPECT_TRUE(throttle.flush().empty()) << "reported once";
}

TEST(LogThrottle, ClassesAreIndependent) {
  FakeClock clock;
  LogThrottle throttle({.burst = 1, .period_ns = 1000 * kMs}, clock.function());
  EXPECT_TRUE(throttle.admit("a", "a1"));
  EXPECT_TRUE(throttle.admit("b", "b1"));
  EXPECT_FALSE(throttle.admit("a", "a2"));
  EXPECT_FALSE(throttle.admit("b", "b2"));
}

TEST(LogThrottle, QuietClassStartsANewBurstAndDueFlushWaitsForThePeriod) {
  FakeClock clock;
  LogThrottle throttle({.burst = 2, .period_ns = 1000 * kMs}, clock.function());
  EXPECT_EQ(throttle.admit("k", "m1").value_or(""), "m1");
  EXPECT_TRUE(throttle.admit("k", "m2"));
  EXPECT_FALSE(throttle.admit("k", "m3"));
  clock.now_ns = 500 * kMs;
  EXPECT_TRUE(throttle.flush(true).empty()) << "not due before a period since the last line";
  clock.now_ns = 1000 * kMs;
  const auto due = throttle.flush(true);
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(due[0], "m3 (repeated 1 time in 1.0 s)");
  // Quiet for more than a period with nothing held back: printed again in full.
  clock.now_ns = 2500 * kMs;
  EXPECT_EQ(throttle.admit("k", "m4").value_or(""), "m4");
}

}  // namespace
}  // namespace heslam::runtime
