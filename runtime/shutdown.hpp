// Process-wide shutdown: SIGINT/SIGTERM handling, and the link to heslam-supervisor.
#pragma once

namespace heslam::runtime {

// Installs SIGINT/SIGTERM handlers that request shutdown (a second SIGINT exits immediately with
// 130; a second SIGTERM is ignored) and, when started by heslam-supervisor ($HESLAM_SUPERVISOR_PID),
// asks the kernel to send SIGTERM to this process when the supervisor dies (PR_SET_PDEATHSIG: no
// orphans even after kill -9) and ignores SIGPIPE, so output to a dead supervisor cannot kill the
// shutdown work.
// Idempotent; call early in main() (Component does it for you).
void install_shutdown_handlers();

// True once shutdown was requested by a signal or request_shutdown().
bool shutdown_requested();

// Requests shutdown from code (thread-safe): wakes every WaitSet with Wake::kShutdown.
void request_shutdown();

// The signal that requested shutdown, or 0.
int shutdown_signal();

}  // namespace heslam::runtime
