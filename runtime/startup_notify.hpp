// The start-up handshake with heslam-supervisor, like systemd's sd_notify: the supervisor hands each
// child a pipe as file descriptor $HESLAM_NOTIFY_FD; a heslam program writes "starting" as soon as
// it installs its signal handlers and "running" once it has configured itself. A program that exits
// with a failure after "starting" but before "running" failed at start-up (bad config, missing
// input, unwritable output): the supervisor does not restart it, since a restart cannot fix that.
// A pipe, not the status topic, because DDS discovery may not have matched before such an exit.
#pragma once

namespace heslam::runtime {

// Environment variable naming the descriptor (unset after it is taken: our children do not inherit it).
inline constexpr const char* kNotifyFdVariable = "HESLAM_NOTIFY_FD";
// The messages, one line each.
inline constexpr const char* kNotifyStarting = "starting";
inline constexpr const char* kNotifyRunning = "running";

// Writes "starting" (first call only). No-op without $HESLAM_NOTIFY_FD. Called by install_shutdown_handlers.
void notify_supervisor_starting();
// Writes "running" (first call only) and closes the descriptor. Called by StatusPublisher on RUNNING.
void notify_supervisor_running();

}  // namespace heslam::runtime
