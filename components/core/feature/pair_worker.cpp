// A persistent second thread for the left/right halves of the per-frame work.
#include "components/core/feature/pair_worker.hpp"

#include <pthread.h>
#include <sched.h>

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

// The first two CPUs the calling thread may run on, or {-1, -1} when it may use fewer than two.
void first_two_allowed_cpus(int (&cpus)[2]) {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (sched_getaffinity(0, sizeof(allowed), &allowed) != 0) return;
  int found = 0;
  for (int cpu = 0; cpu < CPU_SETSIZE && found < 2; ++cpu) {
    if (CPU_ISSET(cpu, &allowed)) cpus[found++] = cpu;
  }
  if (found < 2) cpus[0] = cpus[1] = -1;
}

// Pins the calling thread to `cpu`; false when the kernel refuses (e.g. a cpuset changed meanwhile).
bool pin_this_thread(int cpu) {
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  return pthread_setaffinity_np(pthread_self(), sizeof(one), &one) == 0;
}

}  // namespace

PairWorker::PairWorker(const PairWorkerOptions& options) : options_(options) {
  if (options_.pin_to_two_cpus) first_two_allowed_cpus(cpus_);
  thread_ = std::thread([this] { loop(); });  // after cpus_ is set: the worker reads it
}

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
  if (cpus_[1] >= 0) worker_pinned_.store(pin_this_thread(cpus_[1]), std::memory_order_release);
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
  if (runs_++ == 0 && cpus_[0] >= 0) caller_pinned_ = pin_this_thread(cpus_[0]);
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
