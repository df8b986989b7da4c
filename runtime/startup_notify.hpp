// The start-up handshake with heslam-supervisor, like systemd's sd_notify: the supervisor hands each
// child a pipe as file descriptor $HESLAM_NOTIFY_FD; a heslam program writes "starting" as soon as
// it installs its signal handlers and "running" once it has configured itself, and its result as it
// ends. A program that exits
// with a failure after "starting" but before "running" failed at start-up (bad config, missing
// input, unwritable output): the supervisor does not restart it, since a restart cannot fix that.
// A pipe, not the status topic, because DDS discovery may not have matched before such an exit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>

namespace heslam::runtime {

// Environment variable naming the descriptor (unset after it is taken: our children do not inherit it).
inline constexpr const char* kNotifyFdVariable = "HESLAM_NOTIFY_FD";
// The messages, one line each.
inline constexpr const char* kNotifyStarting = "starting";
inline constexpr const char* kNotifyRunning = "running";

// Writes "starting" (first call only). No-op without $HESLAM_NOTIFY_FD. Called by install_shutdown_handlers.
void notify_supervisor_starting();
// Writes "running" (first call only). Called by StatusPublisher on RUNNING.
void notify_supervisor_running();

// "participant PREFIX" for each DDS participant the program creates (PREFIX: the 24 hex digits of its
// GUID prefix, Participant's constructor). heslam-supervisor trusts status samples of its components
// only from participants its own children named on their pipes (a process that
// copies a component's name, pid and run id is not one it started).
void notify_supervisor_participant(const std::string& guid_prefix);
inline constexpr const char* kNotifyParticipant = "participant";

// The program's result, once, as it ends: its counters ("counter NAME VALUE" lines) and its one-line
// result ("result TEXT", at most kMaxResultBytes). The supervisor's verdict uses these rather than
// the status topic, whose last sample may not arrive before the process is gone, and closes the
// descriptor. Never blocks: a supervisor that stopped reading loses the lines, not the program.
// ended_cleanly (its last state SHUTTING_DOWN, not FAILED): a line "shutting_down" first, so that
// the supervisor may end a run at the result of the component that ends it (docs/supervisor.md, Stopping).
void notify_supervisor_result(const std::map<std::string, std::uint64_t>& counters, const std::string& result,
                              bool ended_cleanly = false);
inline constexpr const char* kNotifyCounter = "counter";
inline constexpr const char* kNotifyResult = "result";
inline constexpr const char* kNotifyShuttingDown = "shutting_down";
inline constexpr std::size_t kMaxResultBytes = 2000;

}  // namespace heslam::runtime
