// For heslam-supervisor only: its own writers (its status) advertise the run it is, its own pid and
// start time (runtime::own_run_id), the run id its components advertise, rather than its parent's.
// Another supervisor then tells a run's supervisor and components apart from anything else, also
// while a killed supervisor's writers wait for their lease to expire.
#pragma once

namespace heslam::runtime {

// Call before any Writer exists: process_run_id() is fixed by its first use.
void adopt_own_run_id();

}  // namespace heslam::runtime
