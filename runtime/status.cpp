// StatusPublisher: a thread that writes ComponentStatus every period (and on every state change).
#include "runtime/status.hpp"

#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <vector>

#include "runtime/sequence.hpp"
#include "runtime/startup_notify.hpp"

namespace heslam::runtime {
namespace {

heslam_msg_ComponentState to_msg(ComponentState state) {
  switch (state) {
    case ComponentState::kConfiguring: return heslam_msg_STATE_CONFIGURING;
    case ComponentState::kRunning: return heslam_msg_STATE_RUNNING;
    case ComponentState::kShuttingDown: return heslam_msg_STATE_SHUTTING_DOWN;
    case ComponentState::kFailed: return heslam_msg_STATE_FAILED;
  }
  return heslam_msg_STATE_FAILED;
}

std::string executable_path() {
  std::error_code error;
  const auto path = std::filesystem::read_symlink("/proc/self/exe", error);
  return error ? std::string{} : path.string();
}

int64_t realtime_ns() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace

uint64_t resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  uint64_t total_pages = 0, resident_pages = 0;
  if (!(statm >> total_pages >> resident_pages)) return 0;
  return resident_pages * static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
}

StatusPublisher::StatusPublisher(const Participant& participant, const Topics& topics, std::string name,
                                 const Stats& stats, std::chrono::milliseconds period)
    : writer_(participant, topics.status()),
      name_(std::move(name)),
      executable_(executable_path()),
      stats_(stats),
      period_(period),
      start_(std::chrono::steady_clock::now()) {
  publish_now();
  thread_ = std::thread([this] { loop(); });
}

StatusPublisher::~StatusPublisher() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  // The end of the program: its final counters and result, for the supervisor's verdict.
  notify_supervisor_result(stats_.counters(), message_, state_ == ComponentState::kShuttingDown);
  try {
    msg::ComponentStatus key{};
    key.name = borrow(name_);
    writer_.unregister(key);
  } catch (...) {
    // Destructors must not throw; the writer's deletion unregisters anyway.
  }
}

void StatusPublisher::set_state(ComponentState state, const std::string& message) {
  {
    std::lock_guard lock(mutex_);
    state_ = state;
    message_ = message;
  }
  if (state == ComponentState::kRunning) notify_supervisor_running();
  publish_now();
}

void StatusPublisher::set_message(const std::string& message) {
  std::lock_guard lock(mutex_);
  message_ = message;
}

void StatusPublisher::publish_now() {
  const auto counters = stats_.counters();
  const auto stages = stats_.stages();
  std::vector<std::string> counter_names;
  std::vector<msg::Counter> counter_values;
  counter_names.reserve(counters.size());
  for (const auto& [counter, value] : counters) {
    counter_names.push_back(counter);
    counter_values.push_back(msg::Counter{borrow(counter_names.back()), value});
  }
  std::vector<msg::StageStats> stage_values;
  for (const auto& stage : stages) {
    stage_values.push_back(msg::StageStats{borrow(stage.name), stage.count, static_cast<float>(stage.p50_ms),
                                           static_cast<float>(stage.p90_ms), static_cast<float>(stage.p99_ms),
                                           static_cast<float>(stage.max_ms)});
  }
  std::lock_guard lock(mutex_);
  msg::ComponentStatus status{};
  status.name = borrow(name_);
  status.pid = static_cast<int32_t>(getpid());
  status.executable = borrow(executable_);
  status.state = to_msg(state_);
  status.uptime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  status.stamp_ns = realtime_ns();
  status.rss_bytes = resident_bytes();
  borrow(status.counters, counter_values);
  borrow(status.stages, stage_values);
  status.message = borrow(message_);
  writer_.write(status);
}

void StatusPublisher::loop() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    if (wake_.wait_for(lock, period_, [this] { return stop_; })) break;
    lock.unlock();
    try {
      publish_now();
    } catch (...) {
      // A failed status write (DDS shutting down) must not kill the component; the next one retries.
    }
    lock.lock();
  }
}

}  // namespace heslam::runtime
