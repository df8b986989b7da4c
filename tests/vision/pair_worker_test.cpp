// PairWorker: both jobs run, every hand-off sees the other thread's writes whether the worker polls
// or sleeps between jobs, exceptions come back to the caller, the worker survives them; the two
// threads pinned to two different CPUs, or left alone when asked.
#include <sched.h>

#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/feature/pair_worker.hpp"

namespace heslam {
namespace {

TEST(PairWorker, ManyHandOffsPollingOrSleepingSeeEachOthersWrites) {
  PairWorker worker;
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<int> values(2, 0);
  std::thread::id worker_thread;
  constexpr int kFrames = 500;
  for (int frame = 1; frame <= kFrames; ++frame) {
    // Three hand-offs per frame as the feature pipeline: two followed by more work, then the last.
    for (PairWorker::Then then : {PairWorker::Then::kMoreSoon, PairWorker::Then::kMoreSoon, PairWorker::Then::kSleep}) {
      const int a = values[0];
      const int b = values[1];
      worker.run(
          [&] {
            worker_thread = std::this_thread::get_id();
            values[1] = a + b + 1;  // reads the caller's write of the previous hand-off
          },
          [&] { values[0] = a + b + 2; }, then);
      ASSERT_EQ(values[0], a + b + 2);
      ASSERT_EQ(values[1], a + b + 1);
      values[0] %= 1000;
      values[1] %= 1000;
    }
  }
  EXPECT_NE(worker_thread, caller);
  EXPECT_EQ(worker.runs(), 3u * kFrames);
  EXPECT_LE(worker.sleeping_hand_offs(), 2u * worker.runs());
}

TEST(PairWorker, NoPollingStillHandsOver) {
  PairWorkerOptions options;
  options.spin = std::chrono::microseconds{0};
  PairWorker worker(options);
  int sum = 0;
  for (int i = 0; i < 200; ++i) {
    int part = 0;
    worker.run([&] { part = i; }, [&] { sum += 1; }, PairWorker::Then::kMoreSoon);
    sum += part;
  }
  EXPECT_EQ(sum, 200 + 199 * 200 / 2);
}

TEST(PairWorker, ExceptionsFromEitherSideReachTheCallerAndTheWorkerGoesOn) {
  PairWorker worker;
  EXPECT_THROW(worker.run([] { throw std::runtime_error("worker"); }, [] {}, PairWorker::Then::kMoreSoon),
               std::runtime_error);
  EXPECT_THROW(worker.run([] {}, [] { throw std::logic_error("caller"); }), std::logic_error);
  // Both throw: the worker's comes first.
  EXPECT_THROW(worker.run([] { throw std::runtime_error("worker"); }, [] { throw std::logic_error("caller"); }),
               std::runtime_error);
  bool ran = false;
  worker.run([&] { ran = true; }, [] {});
  EXPECT_TRUE(ran);
}

// How many CPUs this process may run on.
int allowed_cpus() {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  return sched_getaffinity(0, sizeof(allowed), &allowed) == 0 ? CPU_COUNT(&allowed) : 0;
}

// The caller is a thread of its own, so that its pinning does not outlive the test.
TEST(PairWorker, PinsTheCallerAndTheWorkerToTwoDifferentCpus) {
  if (allowed_cpus() < 2) GTEST_SKIP() << "this process may run on fewer than two CPUs: nothing to pin";
  std::thread caller([] {
    PairWorker worker;
    int worker_cpu = -1;
    int caller_cpu = -1;
    for (int i = 0; i < 20; ++i) {
      worker.run([&] { worker_cpu = sched_getcpu(); }, [&] { caller_cpu = sched_getcpu(); });
      EXPECT_TRUE(worker.pinned());
      EXPECT_EQ(worker_cpu, worker.worker_cpu());
      EXPECT_EQ(caller_cpu, worker.caller_cpu());
    }
    EXPECT_NE(worker.worker_cpu(), worker.caller_cpu());
  });
  caller.join();
}

TEST(PairWorker, LeavesThePlacementToTheSchedulerWhenAsked) {
  std::thread caller([] {
    PairWorkerOptions options;
    options.pin_to_two_cpus = false;
    PairWorker worker(options);
    int runs = 0;
    worker.run([&] { ++runs; }, [&] { ++runs; });
    EXPECT_EQ(runs, 2);
    EXPECT_FALSE(worker.pinned());
    cpu_set_t mine;
    CPU_ZERO(&mine);
    ASSERT_EQ(sched_getaffinity(0, sizeof(mine), &mine), 0);
    EXPECT_EQ(CPU_COUNT(&mine), allowed_cpus());  // the caller's own mask, untouched
  });
  caller.join();
}

}  // namespace
}  // namespace heslam
