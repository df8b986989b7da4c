// A program started by hand that joined a supervisor's run (HESLAM_RUN_ID, runtime/run_self.hpp),
// e.g. a loop closer or a viewer next to a running pipeline, ends with that run: the supervisor's
// own components die with it (PR_SET_PDEATHSIG), a joined one watches the run's supervisor on the
// status topic instead.
//
//   std::optional<runtime::RunEndWatch> run_end;
//   if (runtime::RunEndWatch::joined_by_hand()) run_end.emplace(participant(), topics());
//   ... in the loop: if (run_end) if (auto why = run_end->poll()) { log().info(*why, "; exiting"); break; }
#pragma once

#include <optional>
#include <string>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/topics.hpp"

namespace heslam::runtime {

class RunEndWatch {
 public:
  // Whether this process joined a run by hand: HESLAM_RUN_ID is set (a supervisor never passes it on).
  static bool joined_by_hand();

  RunEndWatch(const Participant& participant, const Topics& topics);

  // Never blocks. Nothing while the run goes on (or before its supervisor was seen); once the run's
  // supervisor (a "supervisor" status written by a writer of this process's run) said SHUTTING_DOWN,
  // or its writer left (killed: its lease expired), one line saying so.
  std::optional<std::string> poll();
  // The run's supervisor's status name once poll() has seen it ("supervisor", "supervisor@HOST"); empty before.
  const std::string& supervisor_name() const { return supervisor_name_; }

 private:
  Reader<msg::ComponentStatus> reader_;
  std::optional<dds_instance_handle_t> supervisor_writer_;
  std::string supervisor_name_;
};

}  // namespace heslam::runtime
