// StatusPublisher: publishes this process's ComponentStatus (state, counts, stage percentiles, RSS)
// right away and then once a period from its own thread. Used by Component; tools may use it too
// so the supervisor sees them ready.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "runtime/participant.hpp"
#include "runtime/stats.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"

namespace heslam::runtime {

enum class ComponentState { kConfiguring, kRunning, kShuttingDown, kFailed };

// Resident set size of this process in bytes (from /proc/self/statm), 0 if unknown.
uint64_t resident_bytes();

class StatusPublisher {
 public:
  StatusPublisher(const Participant& participant, const Topics& topics, std::string name, const Stats& stats,
                  std::chrono::milliseconds period = std::chrono::seconds(1));
  ~StatusPublisher();  // unregisters (readers see the instance go)
  StatusPublisher(const StatusPublisher&) = delete;
  StatusPublisher& operator=(const StatusPublisher&) = delete;

  // Changes the state and publishes immediately. message: the error for kFailed, otherwise the
  // component's one-line result so far (the recorder's "tracked N/M frames, ..."), or empty.
  // kRunning also tells heslam-supervisor's start-up handshake that configuring succeeded.
  void set_state(ComponentState state, const std::string& message = "");
  // Replaces the message without publishing (the next periodic sample carries it).
  void set_message(const std::string& message);
  void publish_now();

 private:
  void loop();

  Writer<msg::ComponentStatus> writer_;
  std::string name_;
  std::string executable_;
  const Stats& stats_;
  std::chrono::milliseconds period_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;  // guards state_, message_, stop_, and serialises writes
  std::condition_variable wake_;
  ComponentState state_ = ComponentState::kConfiguring;
  std::string message_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace heslam::runtime
