// A persistent second thread for the left/right halves of the per-frame work.
#include "components/core/feature/pair_worker.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

// Polls between two reads of the clock: a clock read costs about as much as this many pauses.
constexpr int kPollsPerClockRead = 64;

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#endif
}

}  // namespace

PairWorker::PairWorker(const PairWorkerOptions& options) : options_(options), thread_([this] { loop(); }) {}

PairWorker::~PairWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_.store(true, std::memory_order_relaxed);
    job_posted_.store(true, std::memory_order_release);
  }
  job_posted_cv_.notify_one();
  thread_.join();
}

bool PairWorker::wait_for(const std::atomic<bool>& flag, std::condition_variable& cv, std::chrono::microseconds spin) {
  if (spin.count() > 0) {
    const auto deadline = std::chrono::steady_clock::now() + spin;
    for (int polls = 1; !flag.load(std::memory_order_acquire); ++polls) {
      cpu_relax();
      if (polls % kPollsPerClockRead == 0 && std::chrono::steady_clock::now() >= deadline) break;
    }
  }
  if (flag.load(std::memory_order_acquire)) return false;
  std::unique_lock lock(mutex_);
  if (flag.load(std::memory_order_acquire)) return false;
  cv.wait(lock, [&] { return flag.load(std::memory_order_acquire); });
  return true;
}

void PairWorker::signal(std::atomic<bool>& flag, std::condition_variable& cv) {
  {
    // Set under the mutex: a waiter that checked the flag under it is then already in cv.wait.
    std::lock_guard lock(mutex_);
    flag.store(true, std::memory_order_release);
  }
  cv.notify_one();
}

void PairWorker::loop() {
  std::chrono::microseconds spin{0};  // the first job comes with the first frame: sleep
  while (true) {
    if (wait_for(job_posted_, job_posted_cv_, spin)) sleeping_hand_offs_.fetch_add(1, std::memory_order_relaxed);
    if (stop_.load(std::memory_order_relaxed)) return;
    job_posted_.store(false, std::memory_order_relaxed);
    const std::function<void()>* job = job_;
    spin = then_ == Then::kMoreSoon ? options_.spin : std::chrono::microseconds{0};
    std::exception_ptr error;
    try {
      (*job)();
    } catch (...) {
      error = std::current_exception();
    }
    error_ = error;
    signal(job_done_, job_done_cv_);
  }
}

void PairWorker::run(const std::function<void()>& on_worker, const std::function<void()>& on_caller, Then then) {
  ++runs_;
  job_ = &on_worker;
  then_ = then;
  error_ = nullptr;
  job_done_.store(false, std::memory_order_relaxed);
  signal(job_posted_, job_posted_cv_);
  std::exception_ptr caller_error;
  try {
    on_caller();
  } catch (...) {
    caller_error = std::current_exception();
  }
  if (wait_for(job_done_, job_done_cv_, options_.spin)) sleeping_hand_offs_.fetch_add(1, std::memory_order_relaxed);
  if (error_) std::rethrow_exception(error_);
  if (caller_error) std::rethrow_exception(caller_error);
}

}  // namespace heslam
