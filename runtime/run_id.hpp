// The identity of a pipeline run, for files a restarted component must only resume when its own
// run wrote them (the local mapper's map file, the recorder's journal).
#pragma once

#include <string>

namespace heslam::runtime {

// "<parent pid>:<parent start time>": heslam-supervisor execs its components, so the parent is the
// supervisor, and its pid with its start time never repeat on one machine. A component restarted by
// the same supervisor gets the same id; another run, or the same command run again, another one.
std::string supervisor_run_id();

}  // namespace heslam::runtime
