// A persistent second thread for the left/right halves of the per-frame work.
#include "components/core/feature/pair_worker.hpp"

namespace heslam {

PairWorker::PairWorker() : thread_([this] { loop(); }) {}

PairWorker::~PairWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

void PairWorker::loop() {
  std::unique_lock lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return stop_ || job_ != nullptr; });
    if (stop_) return;
    const std::function<void()>* job = job_;
    lock.unlock();
    std::exception_ptr error;
    try {
      (*job)();
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    error_ = error;
    job_ = nullptr;
    job_done_ = true;
    done_.notify_one();
  }
}

void PairWorker::run(const std::function<void()>& on_worker, const std::function<void()>& on_caller) {
  {
    std::lock_guard lock(mutex_);
    job_ = &on_worker;
    job_done_ = false;
    error_ = nullptr;
  }
  wake_.notify_one();
  std::exception_ptr caller_error;
  try {
    on_caller();
  } catch (...) {
    caller_error = std::current_exception();
  }
  std::unique_lock lock(mutex_);
  done_.wait(lock, [this] { return job_done_; });
  if (error_) std::rethrow_exception(error_);
  if (caller_error) std::rethrow_exception(caller_error);
}

}  // namespace heslam
