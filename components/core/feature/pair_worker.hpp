// Runs two jobs at once: one on a persistent worker thread, one on the caller, and waits for both.
// A persistent thread because starting one per frame costs ~50 us and jitters; the split of work is
// fixed by the caller, so results do not depend on timing.
//
// Hand-offs between the stages of one frame spin briefly before they sleep: a sleeping thread takes
// a futex wake-up (~25 us on the 2-core VM when loaded, more when its vCPU halted) at every stage,
// and a frame has several. Between frames the worker sleeps at once (the caller says which run is
// the frame's last), so the other processes get the core.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>

namespace heslam {

struct PairWorkerOptions {
  // How long a thread waiting for the other (the caller for the worker's job, the worker for the
  // next job of the same frame) polls before it sleeps. The stages of one EuRoC frame hand over
  // within tens of microseconds of each other (the two images' halves are balanced); a longer
  // wait means the other thread was preempted, and polling on would only take its core.
  std::chrono::microseconds spin{200};
  // Keep the caller and the worker on two different CPUs: the first two the process may run on, the
  // caller on the first, the worker on the second (each thread pins itself, the caller at its first
  // run). Left to the scheduler on the 2-core VM, a worker woken after the camera's idle gap was
  // often placed on the caller's CPU and the frame's stages ran one after the other: the frontend
  // paced at 20 Hz took 12.0 ms a frame against 7.4 ms pinned (docs/benchmarks.md at 5c1f792, ninth session).
  // Without two allowed CPUs, or when the kernel refuses, the threads stay unpinned (see pinned()).
  bool pin_to_two_cpus = true;
};

class PairWorker {
 public:
  // What the worker does after its job: wait for another (polling first: the caller has more work
  // for it in this frame, right after its own job) or sleep at once (the frame's last hand-off).
  enum class Then { kSleep, kMoreSoon };

  explicit PairWorker(const PairWorkerOptions& options = {});
  ~PairWorker();
  PairWorker(const PairWorker&) = delete;
  PairWorker& operator=(const PairWorker&) = delete;

  // Runs `on_worker` on the worker thread and `on_caller` here; returns when both are done. An
  // exception from either is rethrown here (the worker's first).
  void run(const std::function<void()>& on_worker, const std::function<void()>& on_caller, Then then = Then::kSleep);

  // Hand-offs so far (runs) and how many of them found the other thread asleep (a futex wake-up),
  // for benchmarks.
  std::uint64_t runs() const { return runs_; }
  std::uint64_t sleeping_hand_offs() const { return sleeping_hand_offs_.load(std::memory_order_relaxed); }
  // Whether both threads run pinned (pin_to_two_cpus, once the first run() has returned), and where.
  bool pinned() const { return caller_pinned_ && worker_pinned_.load(std::memory_order_acquire); }
  int caller_cpu() const { return cpus_[0]; }
  int worker_cpu() const { return cpus_[1]; }

 private:
  void loop();
  // Polls `flag` for `spin`, then sleeps on `cv` until it is set. Returns whether it had to sleep.
  bool wait_for(const std::atomic<bool>& flag, std::condition_variable& cv, std::chrono::microseconds spin);
  // Sets `flag` and wakes a thread sleeping on `cv`.
  void signal(std::atomic<bool>& flag, std::condition_variable& cv);

  PairWorkerOptions options_;
  std::mutex mutex_;
  std::condition_variable job_posted_cv_;
  std::condition_variable job_done_cv_;
  std::atomic<bool> job_posted_{false};
  std::atomic<bool> job_done_{false};
  std::atomic<bool> stop_{false};
  const std::function<void()>* job_ = nullptr;  // written before job_posted_ is set
  Then then_ = Then::kSleep;                    // likewise
  std::exception_ptr error_;                    // written before job_done_ is set
  std::uint64_t runs_ = 0;
  std::atomic<std::uint64_t> sleeping_hand_offs_{0};
  int cpus_[2] = {-1, -1};  // the caller's and the worker's CPU when pinning; -1: not pinned
  bool caller_pinned_ = false;
  std::atomic<bool> worker_pinned_{false};
  std::thread thread_;
};

}  // namespace heslam
