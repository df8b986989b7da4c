// The supervisor's run loop (single-threaded: every spawn happens on the main thread, which
// PR_SET_PDEATHSIG in the children relies on).
#include "runtime/supervisor/supervisor.hpp"

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <sstream>
#include <thread>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/run_id.hpp"
#include "runtime/run_self.hpp"
#include "runtime/sequence.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/stats.hpp"
#include "runtime/status.hpp"
#include "runtime/supervisor/domain_check.hpp"
#include "runtime/supervisor/run_verdict.hpp"
#include "runtime/topics.hpp"
#include "runtime/wire_enum.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::supervisor {
namespace {

using namespace std::chrono_literals;

// Event loop granularity: bounds restart latency and status polling without measurable CPU.
constexpr auto kPumpPeriod = 20ms;
// A component that ran this long before dying is "stable again": its backoff starts over.
constexpr auto kStableRun = 10s;
// After SIGKILL the kernel reaps within milliseconds; this only bounds a pathological wait.
constexpr auto kKillReapTimeout = 2s;

std::string format_seconds(double seconds) {
  std::ostringstream text;
  text << seconds;
  return text.str();
}

// The supervisors of one multi-host run tell each other apart by their status name.
constexpr const char* kSupervisorName = "supervisor";
constexpr const char* kHostSeparator = "@";

// "supervisor" on a single host; "supervisor@HOST" when components run elsewhere (HOST: --host,
// else this machine's name and pid, as --only gives no group name).
std::string supervisor_status_name(const Pipeline& pipeline) {
  if (!pipeline.split()) return kSupervisorName;
  std::string host = pipeline.host;
  if (host.empty()) {
    char name[256] = {};
    gethostname(name, sizeof name - 1);
    host = std::string(name) + ":" + std::to_string(getpid());
  }
  return std::string(kSupervisorName) + kHostSeparator + host;
}

// fps is shown once frames have been published for this long (a shorter span is mostly the status
// period's jitter).
constexpr auto kMinFpsSpan = 500ms;

struct StatusSeen {
  int32_t pid = 0;
  heslam_msg_ComponentState state = heslam_msg_STATE_CONFIGURING;
  std::string message;
  std::uint64_t frames_published = 0;  // the replay's counters, for the progress line
  std::uint64_t frames_total = 0;
  // All of them, for the verdict on a process that could not report its own as it ended.
  std::map<std::string, std::uint64_t> counters;
};

// Before anything starts: how long to listen for another run's writers on the domain (discovery
// over loopback takes milliseconds; a loaded machine, a few hundred), and how long to wait for the
// writers of a run that was killed here to go (their 2 s DDS lease, config/cyclonedds.xml).
constexpr auto kDomainListen = 1000ms;
constexpr auto kKilledRunLinger = 3000ms;

}  // namespace

struct Supervisor::Dds {
  Dds(const Pipeline& pipeline)
      : participant(runtime::ParticipantOptions{pipeline.domain_id, pipeline.dds_config,
                                                pipeline.security_dir.empty()
                                                    ? std::filesystem::path()
                                                    : pipeline.security_dir / "identities" / kSupervisorIdentity}),
        topics(pipeline.ns),
        status_reader(participant, topics.status()),
        status(participant, topics, supervisor_status_name(pipeline), stats),
        status_name(supervisor_status_name(pipeline)) {
    // A run over several hosts has one supervisor per host, each a run of its own: not watched.
    if (!pipeline.split()) watch.emplace(participant.handle(), pipeline.ns, runtime::own_run_id());
  }
  runtime::Participant participant;
  runtime::Topics topics;
  runtime::Reader<msg::ComponentStatus> status_reader;
  runtime::Stats stats;
  runtime::StatusPublisher status;
  std::map<std::string, StatusSeen> seen;
  std::string status_name;             // ours: remote supervisors are the other "supervisor@..." names
  std::optional<OtherRunWatch> watch;  // other runs' writers on the domain (single-host runs)
};

Supervisor::Supervisor(Pipeline pipeline, SupervisorOptions options)
    : pipeline_(std::move(pipeline)),
      options_(std::move(options)),
      log_("supervisor", options_.log_level),
      progress_(options_.progress) {
  dds_ = std::make_unique<Dds>(pipeline_);
  std::filesystem::create_directories(options_.log_dir);
  for (const ComponentSpec& spec : pipeline_.components) {
    auto managed = std::make_unique<Managed>();
    managed->spec = spec;
    name_width_ = std::max(name_width_, spec.name.size());
    components_.push_back(std::move(managed));
  }
  for (const std::string& name : pipeline_.disabled_components) log_.info(name, ": disabled (executable none)");
  for (const ComponentSpec& spec : pipeline_.components) {
    if (spec.remote) log_.info(spec.name, ": runs on another host (not started here)");
  }
}

Supervisor::~Supervisor() = default;

namespace {

// A component's arguments: its own, then the common flags (unless common_args: false).
std::vector<std::string> component_args(const Pipeline& pipeline, const ComponentSpec& spec, runtime::LogLevel level) {
  std::vector<std::string> args = spec.args;
  if (spec.common_args) {
    args.insert(args.end(), {"--domain", std::to_string(pipeline.domain_id), "--namespace", pipeline.ns, "--name",
                             spec.name, "--log-level", std::string(runtime::to_string(level))});
    for (const std::filesystem::path& config : spec.configs) args.insert(args.end(), {"--config", config.string()});
    if (!pipeline.dds_config.empty()) args.insert(args.end(), {"--dds-config", pipeline.dds_config});
    if (pipeline.image_transport == runtime::ImageTransport::kShm) {
      args.insert(args.end(), {"--image-transport", "shm", "--image-domain", std::to_string(pipeline.image_domain_id)});
    }
  }
  return args;
}

// A program's --check opens its inputs (the replay its dataset) and nothing else: this bounds a
// program that ignores the flag and would run.
constexpr auto kProgramCheckTimeout = 30s;

}  // namespace

std::vector<std::string> check_programs(const Pipeline& pipeline, const std::filesystem::path& self_executable) {
  std::vector<std::string> problems;
  const std::string source = pipeline.file.filename().string();
  for (const ComponentSpec& spec : pipeline.components) {
    // heslam's own programs take the common flags, --check among them; others are not asked.
    if (spec.remote || !spec.common_args || !spec.executable.filename().string().starts_with("heslam-")) continue;
    std::vector<std::string> args = component_args(pipeline, spec, runtime::LogLevel::kError);
    args.push_back("--check");
    ChildProcess child = ChildProcess::spawn(self_executable, spec.executable, args, spec.env);
    std::vector<std::string> lines;
    int wait_status = 0;
    bool exited = false;
    const auto deadline = std::chrono::steady_clock::now() + kProgramCheckTimeout;
    while (!exited && std::chrono::steady_clock::now() < deadline) {
      child.read_lines(lines);
      exited = waitpid(child.pid(), &wait_status, WNOHANG) == child.pid();
      if (!exited) std::this_thread::sleep_for(kPumpPeriod);
    }
    child.read_lines(lines);  // the rest: the program has ended
    if (!exited) {
      child.signal_group(SIGKILL);
      waitpid(child.pid(), &wait_status, 0);
      problems.push_back(source + ": component '" + spec.name + "': " + spec.executable.filename().string() +
                         " --check did not finish within " + std::to_string(kProgramCheckTimeout.count()) + " s");
      continue;
    }
    if (WIFEXITED(wait_status) && WEXITSTATUS(wait_status) == 0) continue;
    std::string reason = describe_exit(wait_status);
    for (auto it = lines.rbegin(); it != lines.rend(); ++it) {
      if (it->find_first_not_of(" \t\r") != std::string::npos) {
        reason = *it;
        break;
      }
    }
    problems.push_back(source + ": component '" + spec.name + "': " + reason);
  }
  return problems;
}

std::string describe_run_mode(const Pipeline& pipeline) {
  std::vector<std::string> parts;
  for (const ComponentSpec& spec : pipeline.components) {
    if (spec.executable.filename() != "heslam-replay") continue;
    const auto flag = [&spec](const std::string& name) { return std::find(spec.args.begin(), spec.args.end(), name); };
    if (flag("--lockstep") != spec.args.end()) {
      parts.emplace_back("lockstep");
    } else if (const auto rate = flag("--rate"); rate != spec.args.end() && rate + 1 != spec.args.end()) {
      parts.push_back("real time (rate " + *(rate + 1) + ")");
    } else {
      parts.emplace_back("real time");
    }
    break;
  }
  parts.push_back(pipeline.security_dir.empty() ? "plain DDS (not secure)"
                                                : "secure DDS (" + pipeline.security_dir.string() + ")");
  if (!pipeline.split()) {
    parts.emplace_back("every component on this host");
  } else {
    std::string here, elsewhere;
    for (const ComponentSpec& spec : pipeline.components) {
      std::string& list = spec.remote ? elsewhere : here;
      list += (list.empty() ? "" : ", ") + spec.name;
    }
    parts.push_back((pipeline.host.empty() ? std::string("this host") : "host '" + pipeline.host + "'") + " runs " +
                    (here.empty() ? std::string("none") : here) +
                    "; elsewhere: " + (elsewhere.empty() ? std::string("none") : elsewhere));
  }
  std::string text;
  for (const std::string& part : parts) text += (text.empty() ? "" : ", ") + part;
  return text;
}

std::vector<std::string> Supervisor::child_args(const Managed& component) const {
  return component_args(pipeline_, component.spec, options_.log_level);
}

void Supervisor::start(Managed& component) {
  if (!component.log_file.is_open()) {
    component.log_file.open(options_.log_dir / (component.spec.name + ".log"), std::ios::app);
  }
  std::map<std::string, std::string> env = component.spec.env;
  // Every writer of a run on one host is ours: the components refuse another run's samples.
  if (!pipeline_.split()) env[runtime::kRunOnOneHostVariable] = "1";
  env[runtime::kRestartVariable] = std::to_string(component.restarts);
  // The last words of the process before a restart are still its own.
  component.process.read_notifications();
  component.participants.insert(component.process.participants().begin(), component.process.participants().end());
  component.process = ChildProcess::spawn(options_.self_executable, component.spec.executable, child_args(component),
                                          env, component.spec.nice);
  component.phase = Phase::kRunning;
  component.started_at = Clock::now();
  component.ready = component.spec.ready == Readiness::kStarted;
  component.stopping = false;
  component.killed_at_stop = false;
  component.in_stop_order = false;
  component.pending_exit.reset();
  component.last_line.clear();
  if (component.spec.nice > 0) {
    log_.info("started ", component.spec.name, " (pid ", component.process.pid(), "), nice +", component.spec.nice);
  } else {
    log_.info("started ", component.spec.name, " (pid ", component.process.pid(), ")");
  }
}

std::vector<std::size_t> Supervisor::start_dependencies(std::size_t index) const {
  const ComponentSpec& spec = components_[index]->spec;
  if (!spec.after) return index == 0 ? std::vector<std::size_t>{} : std::vector<std::size_t>{index - 1};
  std::vector<std::size_t> dependencies;
  for (std::size_t other = 0; other < index; ++other) {
    const ComponentSpec& earlier = components_[other]->spec;
    // Another host's component gates every one after it, named or not: that host may start minutes
    // later, longer than a lockstep consumer waits for its acknowledgements.
    if (earlier.remote || std::find(spec.after->begin(), spec.after->end(), earlier.name) != spec.after->end()) {
      dependencies.push_back(other);
    }
  }
  return dependencies;  // a disabled component's name matches none: nothing to wait for
}

bool Supervisor::start_components() {
  // Each component starts once the ones it comes after (`after:`, default the previous one) have
  // settled: ready (its RUNNING status, or spawned for `ready: started`), ended without failing the
  // run, or, for an optional one, given up on. Independent components start together.
  enum class Start { kWaiting, kStarting, kSettled };
  std::vector<Start> state(components_.size(), Start::kWaiting);
  std::vector<Clock::time_point> deadline(components_.size());
  const auto seconds = [](double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  };
  for (;;) {
    bool all_settled = true;
    for (std::size_t i = 0; i < components_.size(); ++i) {
      Managed& component = *components_[i];
      if (state[i] == Start::kSettled) continue;
      all_settled = false;
      if (runtime::shutdown_requested() || end_requested_) return false;
      if (state[i] == Start::kWaiting) {
        const std::vector<std::size_t> dependencies = start_dependencies(i);
        if (!std::all_of(dependencies.begin(), dependencies.end(),
                         [&](std::size_t other) { return state[other] == Start::kSettled; })) {
          continue;
        }
        state[i] = Start::kStarting;
        if (component.spec.remote) {
          if (component.spec.ready == Readiness::kStarted) {
            state[i] = Start::kSettled;
            continue;
          }
          log_.info("waiting for ", component.spec.name, " on another host (its status on the status topic)");
          deadline[i] = Clock::now() + seconds(pipeline_.remote_ready_timeout_s);
        } else {
          try {
            start(component);
          } catch (const std::exception& error) {
            log_.error(error.what());
            if (component.spec.required) {
              fail(error.what());
              return false;
            }
            state[i] = Start::kSettled;
            continue;
          }
          deadline[i] = Clock::now() + seconds(component.spec.ready_timeout_s);
        }
      }
      if (component.spec.remote) {
        if (component.ready) {
          log_.info(component.spec.name, " (another host) is ready");
          state[i] = Start::kSettled;
        } else if (Clock::now() >= deadline[i]) {
          // Not ours to fail: the other host's supervisor reports its own components.
          log_.warn(component.spec.name, ": no RUNNING status from another host within ",
                    pipeline_.remote_ready_timeout_s, " s; starting the next components anyway");
          state[i] = Start::kSettled;
        }
        continue;
      }
      if (component.ready) {
        log_.info(component.spec.name, " is ready");
        state[i] = Start::kSettled;
        continue;
      }
      // Ended while starting: fine for a short-lived program, fatal if it failed and is required.
      if (component.phase == Phase::kEnded) {
        if (failed_) return false;
        state[i] = Start::kSettled;
        continue;
      }
      if (Clock::now() >= deadline[i]) {
        std::ostringstream reason;
        reason << component.spec.name << ": no status within " << component.spec.ready_timeout_s
               << " s (a program that publishes no heslam status needs 'ready: started'; a heslam program built"
                  " from other .idl files cannot talk to this one: rebuild both from the same tree)";
        log_.error(reason.str());
        if (component.spec.required) {
          fail(reason.str());
          return false;
        }
        state[i] = Start::kSettled;
      }
    }
    if (all_settled) return true;
    pump(kPumpPeriod);
  }
}

void Supervisor::forward_output(Managed& component) {
  std::vector<std::string> lines;
  component.process.read_lines(lines);
  if (!lines.empty()) clear_progress();
  for (const std::string& line : lines) {
    std::string prefix = component.spec.name;
    prefix.resize(name_width_, ' ');
    std::cout << prefix << " | " << line << '\n';
    component.log_file << line << '\n';
    if (line.find_first_not_of(" \t\r") != std::string::npos) component.last_line = line;
  }
  if (!lines.empty()) {
    std::cout.flush();
    component.log_file.flush();
  }
}

void Supervisor::read_status() {
  for (auto& received : dds_->status_reader.take()) {
    if (!received.info.valid_data) continue;
    const msg::ComponentStatus& status = *received.sample;
    // A state of no enumerator (runtime/wire_enum.hpp) says nothing about the component: ignored.
    if (!runtime::wire_value_is_one_of(status.state, heslam_msg_STATE_CONFIGURING, heslam_msg_STATE_RUNNING,
                                       heslam_msg_STATE_SHUTTING_DOWN, heslam_msg_STATE_FAILED)) {
      continue;
    }
    const std::string name = runtime::to_string(status.name);
    const auto claimed = std::find_if(components_.begin(), components_.end(), [&](const auto& component) {
      return !component->spec.remote && component->spec.name == name;
    });
    if (claimed != components_.end() &&
        !status_from_child(**claimed, dds_->status_reader.handle(), received.info.publication_handle)) {
      continue;
    }
    StatusSeen& seen = dds_->seen[name];
    seen.pid = status.pid;
    seen.state = status.state;
    seen.message = runtime::to_string(status.message);
    seen.counters.clear();
    for (std::uint32_t i = 0; i < status.counters._length; ++i) {
      const msg::Counter& counter = status.counters._buffer[i];
      const std::string name = runtime::to_string(counter.name);
      if (name == runtime::kFramesPublished) seen.frames_published = counter.value;
      if (name == runtime::kFramesTotal) seen.frames_total = counter.value;
      seen.counters[name] = counter.value;
    }
  }
  follow_remote_hosts();
  follow_remote_end_of_stream();
  for (auto& component : components_) {
    const auto it = dds_->seen.find(component->spec.name);
    if (it == dds_->seen.end()) continue;
    const StatusSeen& seen = it->second;
    if (component->spec.remote) {
      // Another host's process: any pid will do (we never started it); only its readiness matters.
      if (seen.state == heslam_msg_STATE_RUNNING) component->ready = true;
      continue;
    }
    if (seen.pid != component->process.pid()) continue;  // an older instance's last words
    // Kept after the process ended: its last sample may arrive after its exit.
    if (seen.state != heslam_msg_STATE_FAILED && !seen.message.empty()) component->result = seen.message;
    if (component->phase != Phase::kRunning) continue;
    if (!component->ready && seen.state == heslam_msg_STATE_RUNNING) component->ready = true;
    if (seen.state == heslam_msg_STATE_FAILED && seen.message != component->last_reported_failure) {
      component->last_reported_failure = seen.message;
      log_.error(component->spec.name, " reports failure: ", seen.message);
    }
  }
}

bool Supervisor::status_from_child(Managed& component, std::int32_t reader, std::uint64_t writer) {
  const std::optional<std::string> participant = runtime::writer_participant(reader, writer);
  // Gone already (a process that ended right after its last status): nothing can be checked, and its
  // result comes through its pipe anyway.
  if (!participant) return false;
  if (!component.participants.contains(*participant)) {
    component.process.read_notifications();  // its line precedes any status it wrote
    component.participants.insert(component.process.participants().begin(), component.process.participants().end());
  }
  if (component.participants.contains(*participant)) return true;
  ++refused_status_samples_;
  if (!refused_status_writers_.insert(writer).second) return false;
  const std::string run = runtime::writer_run_id(reader, writer).value_or("");
  const std::string who = "a status sample named '" + component.spec.name + "' from " +
                          runtime::describe_writer(reader, writer) + ", a process this supervisor did not start";
  if (run == runtime::process_run_id()) {
    clear_progress();
    log_.error(who, ", with this run's id ", run,
               ": a forged participant; refused (only the processes it started speak for its components)");
    fail("forged status of '" + component.spec.name + "' from a process this supervisor did not start (" +
         runtime::describe_writer(reader, writer) + ", run id copied): refused");
  } else {
    clear_progress();
    log_.warn(who, " (run ", run.empty() ? std::string("none") : run, "): refused");
  }
  return false;
}

void Supervisor::watch_other_runs() {
  if (!dds_->watch || !dds_->watch->poll()) return;
  const std::string others = dds_->watch->describe();
  if (others == other_runs_) return;
  other_runs_ = others;
  clear_progress();
  log_.warn("another heslam run appeared on domain ", pipeline_.domain_id, ": ", others,
            "; this run's components refuse its samples (counted as other_run_writers)");
}

void Supervisor::follow_remote_hosts() {
  if (!pipeline_.split() || end_requested_) return;
  const std::string prefix = std::string(kSupervisorName) + kHostSeparator;
  for (const auto& [name, seen] : dds_->seen) {
    if (name == dds_->status_name || name.rfind(prefix, 0) != 0) continue;
    if (seen.state == heslam_msg_STATE_SHUTTING_DOWN) {
      // One run over several hosts ends together: the host whose replay finished (or that was
      // stopped) ends it for the others.
      // Its failure is its own to report (exit code 1 there); here it is only the reason to stop.
      if (seen.message.empty()) {
        log_.info("the supervisor on host ", name.substr(prefix.size()), " is ending the run; stopping here too");
      } else {
        log_.warn("the supervisor on host ", name.substr(prefix.size()), " is ending the run (", seen.message,
                  "); stopping here too");
      }
      remote_ended_ = true;
      end_requested_ = true;
      return;
    }
  }
}

void Supervisor::follow_remote_end_of_stream() {
  if (!pipeline_.split() || end_requested_) return;
  // The components that end the run together (on_exit: shutdown_with_all, the replays of several agents)
  // on several hosts: the last to end, here or there, ends it. Checked here too, not only when one of ours
  // exits: ours may all have ended before another host's.
  const bool with_all = std::any_of(components_.begin(), components_.end(),
                                    [](const auto& component) { return component->spec.shutdown_with_all; });
  if (with_all && all_shutdown_with_all_ended()) {
    clear_progress();
    log_.info(
        "every component that ends the run together (on_exit: shutdown_with_all) has ended, here or on "
        "another host; stopping");
    end_requested_ = true;
    return;
  }
  // Another host's supervisor ends the run itself when its component ends (follow_remote_hosts).
  const std::string prefix = std::string(kSupervisorName) + kHostSeparator;
  for (const auto& [name, seen] : dds_->seen) {
    if (name != dds_->status_name && name.rfind(prefix, 0) == 0 && seen.state == heslam_msg_STATE_RUNNING) return;
  }
  for (auto& component : components_) {
    if (!component->spec.remote || !component->spec.shutdown_on_exit) continue;
    const auto it = dds_->seen.find(component->spec.name);
    if (it == dds_->seen.end()) continue;
    const StatusSeen& seen = it->second;
    if (seen.state != heslam_msg_STATE_SHUTTING_DOWN && seen.state != heslam_msg_STATE_FAILED) continue;
    clear_progress();
    if (seen.state == heslam_msg_STATE_FAILED) {
      log_.error(component->spec.name,
                 ", which ends the run (on_exit: shutdown), failed outside this supervisor: ", seen.message,
                 "; stopping");
      fail(component->spec.name + " failed outside this supervisor: " + seen.message);
    } else {
      log_.info(component->spec.name, ", which ends the run (on_exit: shutdown), ended outside this supervisor",
                seen.message.empty() ? "" : ": " + seen.message, "; stopping");
    }
    remote_end_ = component->spec.name;
    end_requested_ = true;
    return;
  }
}

void Supervisor::forward_pause_keys() {
  if (!pause_keys_) return;
  const int toggles = pause_keys_->take_toggles();
  if (toggles % 2 == 0) return;
  paused_ = !paused_;
  std::string names;
  for (auto& component : components_) {
    // Not before a heslam program has set up its handlers: SIGUSR1's default action ends a process.
    if (!component->spec.pausable || component->phase != Phase::kRunning ||
        (component->process.said_starting() && !component->process.said_running())) {
      continue;
    }
    kill(component->process.pid(), paused_ ? SIGUSR1 : SIGUSR2);
    names += (names.empty() ? "" : ", ") + component->spec.name;
  }
  clear_progress();
  if (names.empty()) {
    log_.info("space: no pausable component is running here");
    paused_ = false;
  } else {
    log_.info(paused_ ? "paused " : "resumed ", names, paused_ ? " (space resumes)" : "");
  }
}

void Supervisor::report_progress() {
  if (progress_.mode() == RunProgress::Mode::kOff) return;
  RunCounts counts;
  for (const auto& [name, seen] : dds_->seen) {
    counts.published = std::max(counts.published, seen.frames_published);
    counts.total = std::max(counts.total, seen.frames_total);
    if (const std::optional<std::uint64_t> tracked = tracked_from_message(seen.message)) {
      counts.tracked = std::max(counts.tracked.value_or(0), *tracked);
    }
  }
  const Clock::time_point now = Clock::now();
  if (counts.published > 0 && !first_published_) first_published_.emplace(now, counts.published);
  // Measured between the arrivals of new counts (once a status period), not up to now: between two
  // statuses the count stands still and the rate would seem to sink.
  if (counts.published > 0 && (!latest_published_ || latest_published_->second != counts.published)) {
    latest_published_.emplace(now, counts.published);
  }
  if (first_published_ && latest_published_ && latest_published_->first - first_published_->first >= kMinFpsSpan) {
    counts.fps =
        static_cast<double>(latest_published_->second - std::min(latest_published_->second, first_published_->second)) /
        std::chrono::duration<double>(latest_published_->first - first_published_->first).count();
  }
  const std::optional<std::string> line = progress_.update(counts, now);
  if (!line) return;
  if (progress_.mode() == RunProgress::Mode::kPlain) {
    log_.info(*line);
    return;
  }
  std::cerr << "\r\033[K" << *line << std::flush;
  progress_drawn_ = true;
}

void Supervisor::clear_progress() {
  if (!progress_drawn_) return;
  std::cerr << "\r\033[K" << std::flush;
  progress_drawn_ = false;
}

void Supervisor::reap() {
  for (;;) {
    int wait_status = 0;
    const pid_t pid = waitpid(-1, &wait_status, WNOHANG);
    if (pid <= 0) break;
    for (auto& component : components_) {
      if (component->phase != Phase::kRunning || component->process.pid() != pid) continue;
      if (component->in_stop_order) {
        component->pending_exit = wait_status;  // told in stop order
      } else {
        on_exit(*component, wait_status);
      }
    }
  }
  tell_exits();
}

void Supervisor::tell_exits() {
  while (exits_told_ < stop_order_.size()) {
    Managed& component = *stop_order_[exits_told_];
    if (component.phase == Phase::kRunning) {
      if (!component.pending_exit) return;
      on_exit(component, *std::exchange(component.pending_exit, std::nullopt));
    }
    ++exits_told_;
  }
}

void Supervisor::on_exit(Managed& component, int wait_status) {
  clear_progress();
  forward_output(component);
  component.process.read_notifications();
  read_status();  // its last sample may carry its result
  // Anything the program left behind in its group goes with it.
  component.process.signal_group(SIGKILL);
  const bool success = WIFEXITED(wait_status) && WEXITSTATUS(wait_status) == 0;
  const std::string how = describe_exit(wait_status);
  const std::string& name = component.spec.name;
  // A failing heslam program's last line is its one-line reason ("heslam-recorder: ...").
  const std::string why =
      !success && WIFEXITED(wait_status) && !component.last_line.empty() ? ": " + component.last_line : std::string();
  component.phase = Phase::kEnded;
  component.ready = false;
  if (component.stopping) {
    // Our SIGTERM ends a program without handlers; anything else means its shutdown work (the
    // recorder's final files, the mapper's map) did not finish as it should.
    const bool clean = success || (WIFSIGNALED(wait_status) && WTERMSIG(wait_status) == SIGTERM);
    if (clean) {
      log_.info(name, " stopped (", how, ")");
      return;
    }
    const std::string reason =
        component.killed_at_stop
            ? name + " did not stop within " +
                  format_seconds(component.spec.stop_timeout_s.value_or(pipeline_.stop_timeout_s)) +
                  " s and was killed; its shutdown did not finish"
            : name + " failed while stopping (" + how + ")" + why;
    if (component.spec.required) {
      log_.error(reason);
      fail(reason);
    } else {
      log_.warn(reason);
    }
    return;
  }
  // It exited with an error after saying "starting" but before "running" (runtime/startup_notify.hpp):
  // a bad config, a missing input, an unwritable output. Restarting cannot fix that.
  const bool startup_error =
      WIFEXITED(wait_status) && !success && component.process.said_starting() && !component.process.said_running();
  if (startup_error) {
    // A restart that cannot start fails mid-run, not at the run's start-up.
    const std::string reason = component.restarts == 0
                                   ? name + " failed at start-up (" + how + ")" + why
                                   : name + " failed mid-run: restart " + std::to_string(component.restarts) +
                                         " failed at its start-up (" + how + ")" + why;
    log_.error(reason, component.spec.restart == RestartPolicy::kNever
                           ? ""
                           : "; not restarted: a restart cannot fix a start-up error");
    if (component.spec.required) {
      fail(reason);
      end_requested_ = true;
    }
    return;
  }
  const bool wants_restart = component.spec.restart == RestartPolicy::kAlways ||
                             (component.spec.restart == RestartPolicy::kOnFailure && !success);
  if (wants_restart && !end_requested_ && !runtime::shutdown_requested()) {
    if (component.restarts >= component.spec.max_restarts) {
      const std::string reason =
          name + " " + how + why + "; gave up after " + std::to_string(component.restarts) + " restarts";
      log_.error(name, " (pid ", component.process.pid(), ") ", how, "; giving up after ", component.restarts,
                 " restarts");
      if (component.spec.required) {
        fail(reason);
        end_requested_ = true;
      }
      return;
    }
    if (Clock::now() - component.started_at >= kStableRun) component.consecutive_restarts = 0;
    const double delay_s = std::min(component.spec.restart_backoff_max_s,
                                    component.spec.restart_backoff_s * std::pow(2.0, component.consecutive_restarts));
    component.restart_at =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(delay_s));
    component.phase = Phase::kRestartPending;
    ++component.restarts;
    ++component.consecutive_restarts;
    dds_->stats.count("restarts." + name);
    log_.warn(name, " (pid ", component.process.pid(), ") ", how, "; restarting in ", delay_s, " s (restart ",
              component.restarts, " of ", component.spec.max_restarts, ")");
    return;
  }
  if (success) {
    log_.info(name, " finished (", how, ")");
  } else {
    log_.error(name, " (pid ", component.process.pid(), ") ", how, why);
    if (component.spec.required) fail(name + " " + how + why);
  }
  if (component.spec.shutdown_on_exit || (!success && component.spec.required)) end_requested_ = true;
  if (component.spec.shutdown_with_all && all_shutdown_with_all_ended()) end_requested_ = true;
}

bool Supervisor::all_shutdown_with_all_ended() const {
  return std::all_of(components_.begin(), components_.end(), [this](const auto& other) {
    if (!other->spec.shutdown_with_all) return true;
    if (!other->spec.remote) return other->phase == Phase::kEnded;
    // Another host's (an agent's replay there): ended when its status says so.
    const auto it = dds_->seen.find(other->spec.name);
    return it != dds_->seen.end() &&
           (it->second.state == heslam_msg_STATE_SHUTTING_DOWN || it->second.state == heslam_msg_STATE_FAILED);
  });
}

void Supervisor::pump(std::chrono::milliseconds timeout) {
  std::vector<pollfd> fds;
  std::vector<Managed*> owners;
  for (auto& component : components_) {
    if (component->process.output_fd() >= 0) {
      fds.push_back(pollfd{component->process.output_fd(), POLLIN, 0});
      owners.push_back(component.get());
    }
  }
  const std::size_t output_fds = fds.size();
  // The handshake pipes too: a component's "running" wakes the start of the ones after it at once.
  for (auto& component : components_) {
    if (component->process.notify_fd() >= 0) fds.push_back(pollfd{component->process.notify_fd(), POLLIN, 0});
  }
  if (fds.empty()) {
    std::this_thread::sleep_for(timeout);
  } else {
    poll(fds.data(), fds.size(), static_cast<int>(timeout.count()));
  }
  for (std::size_t i = 0; i < output_fds; ++i) {
    if (fds[i].revents != 0) forward_output(*owners[i]);
  }
  for (auto& component : components_) {
    component->process.read_notifications();
    // A heslam program says "running" on its pipe as it publishes its RUNNING status (runtime/status.cpp):
    // ready then, not a status period later when the status topic, volatile, matched after that sample.
    if (component->phase == Phase::kRunning && !component->ready && component->process.said_running()) {
      component->ready = true;
    }
    if (!end_requested_ && ending_by_itself(*component)) end_requested_ = true;
  }
  reap();
  read_status();
  watch_other_runs();
  forward_pause_keys();
  report_progress();
  for (auto& component : components_) {
    if (component->phase == Phase::kRestartPending && Clock::now() >= component->restart_at && !end_requested_ &&
        !runtime::shutdown_requested()) {
      try {
        start(*component);
        clear_progress();
        log_.warn("restarted ", component->spec.name, " (pid ", component->process.pid(), ")");
        dds_->status.publish_now();
      } catch (const std::exception& error) {
        log_.error(error.what());
        component->phase = Phase::kEnded;
        if (component->spec.required) {
          fail(error.what());
          end_requested_ = true;
        }
      }
    }
  }
}

bool Supervisor::anything_alive() const {
  return std::any_of(components_.begin(), components_.end(), [](const auto& component) {
    return component->phase == Phase::kRunning || component->phase == Phase::kRestartPending;
  });
}

bool Supervisor::ending_by_itself(const Managed& component) const {
  return component.phase == Phase::kRunning && !component.stopping && component.spec.shutdown_on_exit &&
         component.process.result() && component.process.said_shutting_down();
}

void Supervisor::stop(Managed& component) {
  if (component.phase == Phase::kRestartPending) component.phase = Phase::kEnded;
  if (component.phase != Phase::kRunning) return;
  // One that ends the run and is ending is not signalled: its exit is waited for (and told) in turn.
  if (!ending_by_itself(component)) {
    component.stopping = true;
    component.process.signal_group(SIGTERM);
  }
  const double stop_timeout_s = component.spec.stop_timeout_s.value_or(pipeline_.stop_timeout_s);
  const auto stop_timeout = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(stop_timeout_s));
  component.stop_deadline = Clock::now() + stop_timeout;
  component.resume_at = Clock::now() + stop_timeout / 2;
  component.resume_checked = false;
  component.in_stop_order = true;
  stop_order_.push_back(&component);
  // A heslam program says its result on its pipe after its shutdown work and its data writers are
  // done (runtime/startup_notify.hpp; a component's writers go before its status): what is left is
  // the DDS teardown of its participant, which the next one's stop overlaps.
  wait_for_stop(component, true);
  if (!component.process.result()) finish_stop(component);  // exited, or did not stop in time: killed now
}

void Supervisor::wait_for_stop(Managed& component, bool until_result) {
  const auto running = [&component] { return component.phase == Phase::kRunning && !component.pending_exit; };
  while (running() && !(until_result && component.process.result()) && Clock::now() < component.stop_deadline) {
    pump(kPumpPeriod);
    // A stopped process (SIGSTOP, a debugger, Ctrl-Z) holds SIGTERM: half-way to the timeout it is
    // resumed, so it still does its shutdown work (the recorder's files, the mapper's map) instead of
    // being killed, and the run's verdict is made of what it really wrote.
    if (!component.resume_checked && running() && Clock::now() >= component.resume_at) {
      component.resume_checked = true;
      if (component.process.stopped()) {
        log_.warn(component.spec.name, " is stopped (SIGSTOP or a debugger); resuming it (SIGCONT) so that it stops");
        component.process.signal_group(SIGCONT);
      }
    }
  }
}

void Supervisor::finish_stop(Managed& component) {
  if (component.phase != Phase::kRunning || !component.in_stop_order) return;
  wait_for_stop(component, false);
  if (component.phase == Phase::kRunning && !component.pending_exit) {
    const double stop_timeout_s = component.spec.stop_timeout_s.value_or(pipeline_.stop_timeout_s);
    log_.warn(component.spec.name, " did not stop within ", stop_timeout_s, " s; sending SIGKILL");
    component.killed_at_stop = true;
    component.process.signal_group(SIGKILL);
    const auto kill_deadline = Clock::now() + kKillReapTimeout;
    while (component.phase == Phase::kRunning && !component.pending_exit && Clock::now() < kill_deadline) {
      pump(kPumpPeriod);
    }
  }
  tell_exits();
}

void Supervisor::stop_all() {
  clear_progress();
  for (auto it = components_.rbegin(); it != components_.rend(); ++it) stop(**it);
  for (Managed* component : stop_order_) finish_stop(*component);
  for (auto& component : components_) {
    forward_output(*component);
    component->process.close_output();
  }
}

int Supervisor::run() {
  log_.info("pipeline '", pipeline_.name, "' on domain ", pipeline_.domain_id, ", namespace '", pipeline_.ns, "', run ",
            runtime::process_run_id(), "; ", describe_run_mode(pipeline_), "; logs in ", options_.log_dir.string());
  std::string pausable;  // the names of the local pausable components
  for (const auto& component : components_) {
    if (component->spec.pausable && !component->spec.remote) {
      pausable += (pausable.empty() ? "" : ", ") + component->spec.name;
    }
  }
  if (!pausable.empty() && options_.keyboard) {
    // A replay told to start paused is paused: the first space resumes it.
    paused_ = std::any_of(components_.begin(), components_.end(), [](const auto& component) {
      const std::vector<std::string>& args = component->spec.args;
      const auto mode = std::find(args.begin(), args.end(), "--start-paused-mode");
      return component->spec.pausable && (std::find(args.begin(), args.end(), "--start-paused") != args.end() ||
                                          (mode != args.end() && mode + 1 != args.end() && *(mode + 1) == "on"));
    });
    pause_keys_ = std::make_unique<PauseKeys>(true);
    if (pause_keys_->active()) {
      log_.info("space on this terminal ", paused_ ? "resumes and pauses " : "pauses and resumes ", pausable,
                paused_ ? " (it starts paused)" : "");
    }
  }
  dds_->status.set_state(runtime::ComponentState::kRunning);
  // Listened for only when another participant may be on the domain: with the built-in
  // configuration, one of this host's that binds a discovery port of the domain.
  if (dds_->watch && other_participant_on_host(pipeline_, pipeline_.domain_id) != false) {
    if (const std::optional<std::string> other = other_run_alive(*dds_->watch, kDomainListen, kKilledRunLinger)) {
      // Both runs would read each other's frames, acknowledgements and results: refused.
      fail("domain " + std::to_string(pipeline_.domain_id) + ", namespace '" + pipeline_.ns +
           "' is in use by another heslam run: " + *other +
           "; stop it, or choose another domain (--domain N, or --domain auto for a free one)");
      log_.error(outcome());
      return 1;
    }
    dds_->watch->forget();
  }
  bool started_all = true;
  if (pipeline_.image_transport == runtime::ImageTransport::kShm) {
    log_.info("stereo images over shared memory on domain ", pipeline_.image_domain_id, ", every other topic on ",
              pipeline_.domain_id);
    try {
      roudi_ = RoudiProcess::ensure(pipeline_.roudi_config, options_.log_dir / "iox-roudi.log", log_);
    } catch (const std::exception& error) {
      log_.error(error.what());
      fail(error.what());
      started_all = false;
    }
  }
  if (started_all) started_all = start_components();
  if (started_all) {
    while (!runtime::shutdown_requested() && !end_requested_ && anything_alive()) pump(kPumpPeriod);
  }
  if (runtime::shutdown_requested()) {
    log_.info("shutdown requested (signal ", runtime::shutdown_signal(), "); stopping in reverse order");
  }
  // Why, for the supervisors of other hosts that follow this one's end (empty: a normal end).
  dds_->status.set_state(runtime::ComponentState::kShuttingDown, failed_ ? "pipeline failed: " + failure_ : "");
  stop_all();
  roudi_.reset();  // after every component that used its shared memory
  read_status();   // the last results
  watch_other_runs();
  judge();
  clear_progress();
  if (failed_) {
    log_.error(outcome());
  } else {
    log_.info(outcome());
  }
  return failed_ ? 1 : 0;
}

void Supervisor::fail(const std::string& reason) {
  if (!failed_) failure_ = reason;
  failed_ = true;
}

void Supervisor::judge() {
  std::vector<ProgramReport> reports;
  for (const auto& component : components_) {
    component->process.read_notifications();
    ProgramReport report;
    report.name = component->spec.name;
    report.result = component->result;
    if (const auto& result = component->process.result()) {
      // Its own last word, through the pipe: never older than what it wrote (a status sample may
      // not arrive before the process is gone).
      report.counters = result->counters;
      if (!result->text.empty() && result->text != component->last_reported_failure) report.result = result->text;
    } else if (const auto seen = dds_->seen.find(component->spec.name); seen != dds_->seen.end()) {
      report.counters = seen->second.counters;
    }
    reports.push_back(std::move(report));
  }
  const RunVerdict verdict = judge_run(reports);
  results_ = verdict.results;
  if (verdict.failure) {
    log_.error(*verdict.failure);
    const std::string reason = *verdict.failure + (results_.empty() ? "" : ": " + results_);
    // Two live writers of one role: nothing else the run says can be trusted, so it comes first.
    if (verdict.writer_conflict && failed_) failure_ = reason + "; also: " + failure_;
    fail(reason);
  }
}

std::string Supervisor::outcome() const {
  if (failed_) return "pipeline failed: " + failure_ + other_runs_note();
  const std::string results = results_ + other_runs_note();
  const char* signal_name = sigabbrev_np(runtime::shutdown_signal());
  const std::string text = remote_ended_ ? "pipeline finished (ended by another host)"
                           : !remote_end_.empty()
                               ? "pipeline finished (" + remote_end_ + " ended outside this supervisor)"
                           : !runtime::shutdown_requested() ? "pipeline finished"
                           : signal_name != nullptr         ? std::string("pipeline stopped by SIG") + signal_name
                                                            : "pipeline stopped";
  return results.empty() ? text : text + ": " + results;
}

std::string Supervisor::other_runs_note() const {
  if (other_runs_.empty()) return "";
  return std::string(results_.empty() && !failed_ ? "" : "; ") + "another heslam run appeared on the domain (" +
         other_runs_ + "), its samples were refused: this run's results are its own";
}

}  // namespace heslam::supervisor
