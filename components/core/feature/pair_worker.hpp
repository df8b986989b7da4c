// Runs two jobs at once: one on a persistent worker thread, one on the caller, and waits for both.
// A persistent thread because starting one per frame costs ~50 us and jitters; the split of work is
// fixed by the caller, so results do not depend on timing.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace heslam {

class PairWorker {
 public:
  PairWorker();
  ~PairWorker();
  PairWorker(const PairWorker&) = delete;
  PairWorker& operator=(const PairWorker&) = delete;

  // Runs `on_worker` on the worker thread and `on_caller` here; returns when both are done. An
  // exception from either is rethrown here (the worker's first).
  void run(const std::function<void()>& on_worker, const std::function<void()>& on_caller);

 private:
  void loop();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void()>* job_ = nullptr;
  bool job_done_ = false;
  bool stop_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace heslam
