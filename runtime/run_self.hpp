// The run a process's writers advertise when it is not its parent's (runtime/run_id.hpp):
// - heslam-supervisor's own writers (its status) advertise the run it is, its own pid and start time
//   (runtime::own_run_id), the run id its components advertise: another supervisor then tells a
//   run's supervisor and components apart from anything else, also while a killed supervisor's
//   writers wait for their lease to expire.
// - A program started by hand joins a running pipeline's run with HESLAM_RUN_ID=<run id> (the
//   supervisor prints it on its first line), e.g. a loop closer started by hand: the run's
//   components take its samples as their own run's instead of refusing them.
#pragma once

#include <cstdint>
#include <cstdlib>

namespace heslam::runtime {

inline constexpr const char* kJoinRunVariable = "HESLAM_RUN_ID";

// How many times the supervisor restarted this component before starting this process (0: its
// first start, or not started by a supervisor). A process that allocates ids for the run's map
// starts each restart in an id range of its own, so ids never collide with an earlier incarnation's
// whatever files it lost.
inline constexpr const char* kRestartVariable = "HESLAM_RESTART";
inline std::uint64_t restart_number() {
  const char* text = std::getenv(kRestartVariable);
  if (text == nullptr || *text == '\0') return 0;
  char* end = nullptr;
  const unsigned long long value = std::strtoull(text, &end, 10);
  return end != nullptr && *end == '\0' ? value : 0;
}

// heslam-supervisor, before any Writer exists (process_run_id() is fixed by its first use); also
// drops HESLAM_RUN_ID from its environment, so that its components never inherit another run's.
void adopt_own_run_id();

}  // namespace heslam::runtime
