// The identity of a pipeline run, for files a restarted component must only resume when its own
// run wrote them (the local mapper's map file, the recorder's journal), and for the writers of a run:
// every Writer carries it in its user data, so a single-writer reader (runtime/checked_reader.hpp)
// lets only a writer of the stream owner's run take the topic over (a restarted publisher).
#pragma once

#include <string>
#include <string_view>

namespace heslam::runtime {

// "<parent pid>:<parent start time>": heslam-supervisor execs its components, so the parent is the
// supervisor, and its pid with its start time never repeat on one machine. A component restarted by
// the same supervisor gets the same id; another run, or the same command run again, another one.
std::string supervisor_run_id();

// What this process's writers advertise, read once: supervisor_run_id() (runtime/run_self.hpp).
const std::string& process_run_id();

// Set (to "1") by heslam-supervisor for the components of a run that runs entirely on this host:
// every legitimate writer of the run's topics is then of this run, so a reader refuses the samples
// of any writer of another run, even one that wrote first (another run on the same domain). Unset
// (a multi-host run, whose hosts' supervisors are different runs, or a component started by hand):
// the first writer owns a topic, whatever its run (runtime/checked_reader.hpp).
inline constexpr const char* kRunOnOneHostVariable = "HESLAM_RUN_ON_ONE_HOST";
bool run_on_one_host();

// The run id this process gives its own children ("<pid>:<start time>" of this process): what
// heslam-supervisor's components advertise, so the supervisor can tell them from another run's.
std::string own_run_id();

// A writer's user data is this prefix followed by its run id (other user data is not a run id).
inline constexpr std::string_view kRunUserDataPrefix = "heslam-run=";

}  // namespace heslam::runtime
