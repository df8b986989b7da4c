// ChildProcess: one spawned program in its own process group, its stdout+stderr on a pipe.
//
// Spawned through the supervisor's own binary in "--exec-child" mode, which sets PR_SET_PDEATHSIG
// before exec'ing the program, so even a program that knows nothing of heslam dies with the
// supervisor (kill -9 included). A second pipe, as file descriptor 3, carries the start-up handshake
// and the program's final result.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace heslam::supervisor {

class ChildProcess {
 public:
  // Throws std::runtime_error("cannot start PROGRAM: reason"). nice_increment (>= 0) is added to the
  // niceness by the trampoline before exec, so every thread the program starts inherits it.
  static ChildProcess spawn(const std::filesystem::path& trampoline, const std::filesystem::path& program,
                            const std::vector<std::string>& args, const std::map<std::string, std::string>& env,
                            int nice_increment = 0);

  ChildProcess() = default;
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess();  // closes the pipe; never kills (the supervisor decides that)

  pid_t pid() const { return pid_; }
  int output_fd() const { return output_fd_; }
  int notify_fd() const { return notify_fd_; }

  // The start-up handshake (runtime/startup_notify.hpp): reads what the program wrote so far
  // (non-blocking); closes the pipe at its end.
  void read_notifications();
  bool said_starting() const { return said_starting_; }  // a heslam program: it speaks the handshake
  bool said_running() const { return said_running_; }    // configured itself successfully
  // What a heslam program said as it ended (runtime/startup_notify.hpp): its final counters and its
  // one-line result. Unset for a program killed before it could say it, or not heslam's.
  struct Result {
    std::map<std::string, std::uint64_t> counters;
    std::string text;
  };
  const std::optional<Result>& result() const { return result_; }
  // Its result came after a clean end (its last state SHUTTING_DOWN, not FAILED).
  bool said_shutting_down() const { return said_shutting_down_; }
  // The GUID prefixes of the DDS participants the program said it created ("participant" lines).
  const std::set<std::string>& participants() const { return participants_; }

  // Reads what is available (non-blocking) and returns complete lines; at end of stream also the
  // unterminated rest. Returns false once the stream is closed.
  bool read_lines(std::vector<std::string>& lines);
  void close_output();

  // Whether the program is stopped (SIGSTOP, SIGTSTP, a tracer), from /proc/PID/stat.
  bool stopped() const;

  // Signals the whole process group (the program and anything it started).
  void signal_group(int signal_number) const;

 private:
  void read_result_line(const std::string& line);

  pid_t pid_ = 0;
  int output_fd_ = -1;
  int notify_fd_ = -1;
  bool said_starting_ = false;
  bool said_running_ = false;
  bool said_shutting_down_ = false;
  std::string partial_;
  std::string notify_partial_;
  Result pending_result_;  // counters read so far; complete with the "result" line
  std::optional<Result> result_;
  std::set<std::string> participants_;
};

// The --exec-child mode of heslam-supervisor: never returns (exec or _exit(127)).
[[noreturn]] void exec_child(int argc, char** argv);

// "exit code 3", "killed by SIGKILL" for a waitpid status.
std::string describe_exit(int wait_status);

}  // namespace heslam::supervisor
