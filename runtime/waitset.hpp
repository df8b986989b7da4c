// WaitSet: block until an attached reader has data, a timeout passes, or shutdown is requested.
//
// Every WaitSet owns a guard condition that runtime::request_shutdown() (and SIGINT/SIGTERM via
// runtime/shutdown.hpp) triggers, so a component blocked in wait() ends promptly and cleanly.
#pragma once

#include <chrono>
#include <vector>

#include "runtime/entity.hpp"
#include "runtime/participant.hpp"

namespace heslam::runtime {

enum class Wake {
  kData,      // at least one attached reader has samples (see ready())
  kTimeout,   // nothing within the timeout
  kShutdown,  // shutdown requested (signal or request_shutdown()); leave the loop
  kWoken,     // wake() was called from another thread
};

// Which readers a WaitSet may attach: those of its participant, or of any participant of the process
// (a frontend whose images arrive on a shared-memory domain of their own, runtime/image_transport.hpp).
enum class WaitScope { kParticipant, kAllDomains };

class WaitSet {
 public:
  explicit WaitSet(const Participant& participant, WaitScope scope = WaitScope::kParticipant);
  ~WaitSet();
  WaitSet(const WaitSet&) = delete;
  WaitSet& operator=(const WaitSet&) = delete;

  // Wakes while the reader holds any sample (a read condition on any state). Returns a token
  // identifying the reader in ready().
  int attach(dds_entity_t reader);
  template <typename ReaderT>
  int attach(const ReaderT& reader) {
    return attach(reader.handle());
  }

  Wake wait(std::chrono::nanoseconds timeout);
  // Tokens of readers that had data at the last kData wake.
  const std::vector<int>& ready() const { return ready_; }

  // Makes a concurrent or the next wait() return kWoken (thread-safe).
  void wake();

 private:
  dds_entity_t participant_;
  Entity waitset_;
  Entity wake_guard_;
  Entity shutdown_guard_;
  std::vector<Entity> conditions_;
  std::vector<int> ready_;
};

}  // namespace heslam::runtime
