// RunEndWatch: tells a process that watches a run from outside it (a viewer or a spy started by hand,
// not by the run's supervisor) when that run ended, from the status topic alone.
//
// A run's end is visible on system/status: its supervisor (status name "supervisor", or
// "supervisor@HOST" on a run over several hosts) publishes STATE_SHUTTING_DOWN before it stops its
// components; a run without a supervisor (a replay started by hand) ends when its replay publishes
// STATE_SHUTTING_DOWN (the replay does so when its last frame is done). A replay killed and restarted
// publishes no such state, and once a supervisor was seen only the supervisor's end counts (the
// local mapper's final map is published after the replay ended).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/topics.hpp"

namespace heslam::runtime {

// The rule above, on plain values (unit-testable without DDS).
class RunEndRule {
 public:
  // One valid status sample: the publisher's status name, its executable (a path or a bare name)
  // and whether its state is STATE_SHUTTING_DOWN.
  void observe(std::string_view name, std::string_view executable, bool shutting_down);
  // Set once the run ended: why, for a log line ("the supervisor is ending the run").
  const std::optional<std::string>& ended() const { return ended_; }

 private:
  bool supervisor_seen_ = false;
  std::optional<std::string> ended_;
};

class RunEndWatch {
 public:
  RunEndWatch(const Participant& participant, const Topics& topics);

  // Takes the status samples that arrived; true once the run ended (and from then on).
  bool poll();
  const std::optional<std::string>& reason() const { return rule_.ended(); }
  // For a WaitSet: the status reader wakes it when a sample arrives.
  const Reader<msg::ComponentStatus>& reader() const { return reader_; }

 private:
  Reader<msg::ComponentStatus> reader_;
  RunEndRule rule_;
};

}  // namespace heslam::runtime
