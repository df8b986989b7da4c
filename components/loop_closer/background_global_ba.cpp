// The loop closer's global bundle adjustment thread (see background_global_ba.hpp).
#include "components/loop_closer/background_global_ba.hpp"

#include <ctime>
#include <utility>

namespace heslam::loop_closer {

namespace {

double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

}  // namespace

void BackgroundGlobalBa::start(const LoopClosing& closing, Map map, KeyframeId loop_kf,
                               std::optional<GlobalInertialInput> inertial) {
  abort();
  stop_ = false;
  done_ = false;
  result_.reset();
  stats_ = {};
  cpu_ms_ = 0.0;
  started_ = std::chrono::steady_clock::now();
  thread_ = std::thread([this, &closing, map = std::move(map), loop_kf, inertial = std::move(inertial)] {
    const double cpu_start = thread_cpu_ms();
    result_ = closing.global_bundle_adjustment(map, &stop_, inertial ? &*inertial : nullptr, &stats_);
    if (result_) result_->loop_kf = loop_kf;
    cpu_ms_ = thread_cpu_ms() - cpu_start;
    done_ = true;
  });
}

bool BackgroundGlobalBa::abort() {
  if (!thread_.joinable()) return false;
  stop_ = true;
  thread_.join();
  result_.reset();
  return true;
}

BackgroundGlobalBa::Outcome BackgroundGlobalBa::collect() {
  Outcome outcome;
  if (!thread_.joinable()) return outcome;
  thread_.join();
  outcome.correction = std::move(result_);
  result_.reset();
  outcome.stats = stats_;
  outcome.cpu_ms = cpu_ms_;
  outcome.elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started_).count();
  return outcome;
}

}  // namespace heslam::loop_closer
