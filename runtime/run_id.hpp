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

// supervisor_run_id() of this process, read once (what its writers advertise).
const std::string& process_run_id();

// A writer's user data is this prefix followed by its run id (other user data is not a run id).
inline constexpr std::string_view kRunUserDataPrefix = "heslam-run=";

}  // namespace heslam::runtime
