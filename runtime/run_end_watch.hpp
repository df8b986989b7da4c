// RunEndWatch: tells a process that watches or joined a run from outside its supervisor (a viewer, a
// loop closer or a spy started by hand) when that run ended, from the status topic alone. The
// supervisor's own components need none of this: they die with it (PR_SET_PDEATHSIG).
//
// A run's end is visible on system/status: its supervisor (status name "supervisor", or
// "supervisor@HOST" on a run over several hosts) publishes STATE_SHUTTING_DOWN before it stops its
// components, and a supervisor killed outright is gone from DDS once its lease expires. A process that
// joined a run (HESLAM_RUN_ID, runtime/run_self.hpp) listens only to that run's supervisor. A run
// without a supervisor (a replay started by hand) ends when its replay publishes STATE_SHUTTING_DOWN
// (it does so when its last frame is done); once a supervisor was seen only the supervisor's end
// counts (the local mapper's final map is published after the replay ended).
//
//   std::optional<runtime::RunEndWatch> run_end;
//   if (runtime::RunEndWatch::joined_by_hand()) run_end.emplace(participant(), topics());
//   ... in the loop: if (auto why = run_end->poll()) { log().info(*why, "; exiting"); break; }
#pragma once

#include <optional>
#include <set>
#include <string>
#include <string_view>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/topics.hpp"

namespace heslam::runtime {

// The rule above on plain values (unit-testable without DDS).
class RunEndRule {
 public:
  // One valid status sample: the publisher's status name, its executable (a path or a bare name)
  // and whether its state is STATE_SHUTTING_DOWN.
  void observe(std::string_view name, std::string_view executable, bool shutting_down);
  // The supervisor that was seen leaving without saying so (its writer is gone).
  void supervisor_gone(std::string_view name);
  static bool is_supervisor(std::string_view name, std::string_view executable);
  // Set once the run ended: why, for a log line ("the supervisor (supervisor) is ending the run").
  const std::optional<std::string>& ended() const { return ended_; }

 private:
  bool supervisor_seen_ = false;
  std::optional<std::string> ended_;
};

class RunEndWatch {
 public:
  // Whether this process joined a run by hand: HESLAM_RUN_ID is set (a supervisor never passes it on).
  static bool joined_by_hand();

  RunEndWatch(const Participant& participant, const Topics& topics);

  // Never blocks: takes the status samples that arrived; nothing while the run goes on, then (from
  // then on) one line saying why it ended.
  std::optional<std::string> poll();
  // The run's supervisor's status name once poll() has seen it ("supervisor", "supervisor@HOST"); empty before.
  const std::string& supervisor_name() const { return supervisor_name_; }
  // For a WaitSet: the status reader wakes it when a sample arrives.
  const Reader<msg::ComponentStatus>& reader() const { return reader_; }

 private:
  Reader<msg::ComponentStatus> reader_;
  bool joined_ = false;
  RunEndRule rule_;
  // Whether a writer is of the joined run, remembered: a supervisor's last sample ("ending the run")
  // may be taken after its writer left, when the run it advertised can no longer be asked.
  bool of_joined_run(dds_instance_handle_t writer);
  std::set<dds_instance_handle_t> joined_run_writers_;
  std::optional<dds_instance_handle_t> supervisor_writer_;
  std::string supervisor_name_;
};

}  // namespace heslam::runtime
