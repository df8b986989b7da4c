// Signals -> shutdown. The handler only stores the signal and writes one byte to a pipe
// (async-signal-safe); a watcher thread turns that into guard-condition triggers, which take locks.
#include "runtime/shutdown.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "runtime/shutdown_registry.hpp"
#include "runtime/startup_notify.hpp"

namespace heslam::runtime {
namespace {

std::atomic<int> g_signal{0};
std::atomic<bool> g_requested{false};
int g_pipe[2] = {-1, -1};

std::mutex& registry_mutex() {
  static std::mutex mutex;
  return mutex;
}
std::set<dds_entity_t>& registry() {
  static std::set<dds_entity_t> guards;
  return guards;
}

void trigger_all() {
  std::lock_guard lock(registry_mutex());
  for (dds_entity_t guard : registry()) dds_set_guardcondition(guard, true);
}

extern "C" void on_signal(int signal_number) {
  // A second Ctrl-C: the user insists. A second SIGTERM is not a user: the kernel's parent-death
  // signal (PR_SET_PDEATHSIG) follows the supervisor's own SIGTERM when the supervisor is killed or
  // interrupted twice, and must not cut short the shutdown work (the recorder's final files).
  if (g_requested.exchange(true)) {
    if (signal_number == SIGINT) _exit(128 + signal_number);
    return;
  }
  g_signal.store(signal_number);
  const char byte = 1;
  [[maybe_unused]] const ssize_t ignored = ::write(g_pipe[1], &byte, 1);
}

void watch_pipe() {
  char byte = 0;
  while (::read(g_pipe[0], &byte, 1) < 0) {
  }
  trigger_all();
}

// Started by heslam-supervisor: die with it (the kernel sends SIGTERM when the parent goes).
void bind_to_supervisor() {
  const char* text = std::getenv("HESLAM_SUPERVISOR_PID");
  if (text == nullptr || *text == '\0') return;
  const std::string supervisor_pid = text;
  // Only our direct parent is the supervisor: programs we start must not inherit the binding.
  unsetenv("HESLAM_SUPERVISOR_PID");
  prctl(PR_SET_PDEATHSIG, SIGTERM);
  // Our output is a pipe to the supervisor: when it dies (kill -9, a double Ctrl-C) the next log line
  // would raise SIGPIPE and kill us in the middle of the shutdown work (the recorder's final files).
  // Only under the supervisor: a tool piped into `head` on a terminal should still end with the pipe.
  signal(SIGPIPE, SIG_IGN);
  // The supervisor may have died between our spawn and the prctl: then nobody will send the signal.
  if (std::to_string(getppid()) != supervisor_pid) request_shutdown();
}

}  // namespace

void install_shutdown_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (pipe2(g_pipe, O_CLOEXEC) != 0) std::abort();
    std::thread(watch_pipe).detach();
    struct sigaction action {};
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
    bind_to_supervisor();
    notify_supervisor_starting();
  });
}

bool shutdown_requested() { return g_requested.load(); }

void request_shutdown() {
  g_requested.store(true);
  trigger_all();
}

int shutdown_signal() { return g_signal.load(); }

namespace detail {

void register_shutdown_guard(dds_entity_t guard) {
  std::lock_guard lock(registry_mutex());
  registry().insert(guard);
  if (g_requested.load()) dds_set_guardcondition(guard, true);
}

void unregister_shutdown_guard(dds_entity_t guard) {
  std::lock_guard lock(registry_mutex());
  registry().erase(guard);
}

}  // namespace detail
}  // namespace heslam::runtime
