// Supervisor: runs a Pipeline — start in order with readiness, forward and log output, restart per
// policy with backoff, stop in reverse order (SIGTERM, then SIGKILL), exit code from the outcome.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "runtime/log.hpp"
#include "runtime/supervisor/child_process.hpp"
#include "runtime/supervisor/pause_keys.hpp"
#include "runtime/supervisor/pipeline.hpp"
#include "runtime/supervisor/roudi_process.hpp"
#include "runtime/supervisor/run_progress.hpp"

namespace heslam::supervisor {

struct SupervisorOptions {
  std::filesystem::path self_executable;  // the exec trampoline (this binary)
  std::filesystem::path log_dir;          // per-component logs go here
  runtime::LogLevel log_level = runtime::LogLevel::kInfo;
  // The run's progress line (run_progress.hpp): kLive on a terminal, kPlain (a line per 10 %) otherwise.
  RunProgress::Mode progress = RunProgress::Mode::kOff;
  // Space on the supervisor's terminal pauses / resumes the pausable components (--no-keyboard: off).
  bool keyboard = true;
};

// The start line's account of how the run runs: "lockstep" or "real time" (from the replay's
// arguments; nothing without a replay), "plain DDS" or "secure (DIR)", and which components this
// host runs when others run elsewhere ("all on this host" otherwise).
std::string describe_run_mode(const Pipeline& pipeline);

// --check: runs each heslam program of the pipeline (on this host) with its arguments and --check,
// which checks them (and its config, its inputs) as its start would; one problem per program that
// refuses them: "FILE: component 'NAME': its one-line error".
std::vector<std::string> check_programs(const Pipeline& pipeline, const std::filesystem::path& self_executable);

class Supervisor {
 public:
  Supervisor(Pipeline pipeline, SupervisorOptions options);
  ~Supervisor();
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;

  // Runs until the pipeline ends or shutdown is requested; 0 = success, 1 = a required component failed
  // (at start-up, while running, or while stopping).
  int run();

 private:
  using Clock = std::chrono::steady_clock;
  enum class Phase { kIdle, kRunning, kRestartPending, kEnded };

  struct Managed {
    ComponentSpec spec;
    Phase phase = Phase::kIdle;
    ChildProcess process;
    std::ofstream log_file;
    Clock::time_point started_at{};
    Clock::time_point restart_at{};
    int restarts = 0;
    int consecutive_restarts = 0;
    bool ready = false;
    bool stopping = false;              // we sent SIGTERM: the exit is expected
    bool killed_at_stop = false;        // did not stop within stop_timeout_s: we sent SIGKILL
    Clock::time_point stop_deadline{};  // our SIGTERM + its stop timeout: then SIGKILL
    Clock::time_point resume_at{};      // half-way: a stopped process is resumed (SIGCONT)
    bool resume_checked = false;
    bool in_stop_order = false;       // stopped (or ending by itself) in stop_all: its exit told in order
    std::optional<int> pending_exit;  // its wait status, while exits are told in stop order (tell_exits)
    std::string last_reported_failure;
    std::string last_line;  // of its output: a failing heslam program's one-line reason
    std::string result;     // the one-line result in its latest status (the recorder's "tracked N/M ...")
    // GUID prefixes of the DDS participants its processes (this one and those before a restart)
    // named on their pipes: its status is taken only from these.
    std::set<std::string> participants;
  };

  struct Dds;  // participant, status reader and writer (pimpl: keeps DDS out of this header)

  void start(Managed& component);
  // Starts the components, each once those it comes after are ready (`after:`; a component of
  // another host is waited for on the status topic, bounded, never a failure here); false when the
  // run failed or was ended meanwhile.
  bool start_components();
  // The indexes of the components `components_[index]` waits for before it starts.
  std::vector<std::size_t> start_dependencies(std::size_t index) const;
  // Multi-host (docs/deployment.md): ends this side when another host's supervisor ends the run.
  void follow_remote_hosts();
  void pump(std::chrono::milliseconds timeout);  // output, exits, status, due restarts
  void forward_output(Managed& component);
  void reap();
  void on_exit(Managed& component, int wait_status);
  void read_status();
  // Whether a status sample claiming `component`'s name was written by a process this supervisor
  // started as it (its participant, announced on its pipe). Another one is refused: counted, named
  // once, and the run fails when it carries this run's id (a forger that copied it).
  // (`reader`, `writer`: the DDS reader's entity and the sample's publication handle.)
  bool status_from_child(Managed& component, std::int32_t reader, std::uint64_t writer);
  // Shows the run's progress from the latest statuses (live redraw or a plain line per 10 %).
  void report_progress();
  // Before any other output: wipes a live progress line so the output starts on a clean line.
  void clear_progress();
  // Stops the components in reverse start order: each gets SIGTERM once the one before it has done
  // its shutdown work (said its result on its pipe, or exited); their DDS teardowns overlap, and
  // their exits are told in that order.
  void stop_all();
  // SIGTERM, then waits until it said its result or exited (or its stop timeout: then SIGKILL).
  void stop(Managed& component);
  // Waits while it runs (until_result: and has not said its result yet), up to its stop timeout;
  // resumes it half-way if it is stopped (SIGSTOP, a debugger).
  void wait_for_stop(Managed& component, bool until_result);
  // Waits for its exit: the rest of its stop timeout, then SIGKILL.
  void finish_stop(Managed& component);
  // Tells (on_exit) the exits of the stopping components in their stop order, as far as they exited.
  void tell_exits();
  // A component that ends the run (on_exit: shutdown), not stopped by us, that said its result after
  // a clean end: only its DDS teardown is left, the run's stop need not wait for its exit to begin.
  bool ending_by_itself(const Managed& component) const;
  std::vector<std::string> child_args(const Managed& component) const;
  bool anything_alive() const;
  // Marks the run failed (exit code 1) for this reason, unless an earlier failure is already the reason.
  void fail(const std::string& reason);
  // The last line: what the run produced, or why it failed.
  std::string outcome() const;
  // Mid-run: notes another run's writers appearing on the domain (single-host runs).
  void watch_other_runs();
  // At the end: the verdict from what the programs reported (run_verdict.hpp); fails the run when an
  // output lacks what was produced.
  void judge();
  std::string other_runs_note() const;
  // Space on the terminal: SIGUSR1 / SIGUSR2 to the pausable components (pause_keys.hpp).
  void forward_pause_keys();
  // A component that ends the run (on_exit: shutdown) but runs outside any supervisor (started by
  // hand next to an --only run): its SHUTTING_DOWN status ends this run as its exit would.
  void follow_remote_end_of_stream();
  // Every component with on_exit: shutdown_with_all has ended: ours exited, another host's reported
  // SHUTTING_DOWN or FAILED on the status topic.
  bool all_shutdown_with_all_ended() const;

  Pipeline pipeline_;
  SupervisorOptions options_;
  runtime::Logger log_;
  std::unique_ptr<Dds> dds_;
  // image_transport shm: the iox-roudi this supervisor started (null: udp, or one was running already);
  // stopped after the components.
  std::unique_ptr<RoudiProcess> roudi_;
  std::vector<std::unique_ptr<Managed>> components_;
  std::vector<Managed*> stop_order_;  // the components stopped so far, in order
  std::size_t exits_told_ = 0;        // of stop_order_
  std::size_t name_width_ = 0;
  bool failed_ = false;
  std::string failure_;  // the first reason the run failed
  bool end_requested_ = false;
  bool remote_ended_ = false;                       // another host's supervisor ended the run
  std::string results_;                             // the programs' results, from judge()
  std::string other_runs_;                          // other runs seen on the domain mid-run (OtherRunWatch::describe)
  std::set<std::uint64_t> refused_status_writers_;  // publication handles, named once each
  std::uint64_t refused_status_samples_ = 0;
  RunProgress progress_;
  bool progress_drawn_ = false;  // a live line is on the terminal
  // The first status with frames published: fps is measured from there.
  std::optional<std::pair<Clock::time_point, std::uint64_t>> first_published_;
  std::optional<std::pair<Clock::time_point, std::uint64_t>> latest_published_;  // the latest new count
  std::unique_ptr<PauseKeys> pause_keys_;  // created by run(), so the terminal is restored as it returns
  bool paused_ = false;                    // the pausable components were last told to pause
  std::string remote_end_;                 // which remote component ended the run, and its result
};

}  // namespace heslam::supervisor
