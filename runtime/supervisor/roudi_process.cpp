// RoudiProcess: start iox-roudi in its own process group (a terminal's Ctrl-C must not end it before
// the components that use its shared memory), wait for "ready for clients", SIGTERM it at the end.
#include "runtime/supervisor/roudi_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "runtime/image_transport.hpp"

extern char** environ;

namespace heslam::supervisor {
namespace {

using Clock = std::chrono::steady_clock;

// RouDi maps its mempools (config/iceoryx/roudi.toml: ~100 MB) before it takes clients; well under 1 s
// here, 10 s leaves room for a loaded machine.
constexpr std::chrono::seconds kReadyTimeout{10};
// RouDi releases its shared memory on SIGTERM; SIGKILL after this long.
constexpr std::chrono::seconds kStopTimeout{5};
constexpr const char* kReadyLine = "RouDi is ready for clients";

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

bool wait_exit(pid_t pid, std::chrono::steady_clock::duration timeout) {
  const auto deadline = Clock::now() + timeout;
  while (Clock::now() < deadline) {
    if (waitpid(pid, nullptr, WNOHANG) == pid) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

}  // namespace

std::unique_ptr<RoudiProcess> RoudiProcess::ensure(const std::filesystem::path& config,
                                                   const std::filesystem::path& log_file, const runtime::Logger& log) {
  if (runtime::iox_roudi_running()) {
    log.info("image transport shm: using the iox-roudi already running on this host");
    return nullptr;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attributes, 0);
  std::vector<std::string> args = {"iox-roudi", "-c", config.string(), "-l", "warning"};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, argv[0], &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (error == ENOENT) {
    throw std::runtime_error("image transport shm: iox-roudi not found on PATH (apt-get install iceoryx)");
  }
  if (error != 0)
    throw std::runtime_error(std::string("image transport shm: cannot start iox-roudi: ") + std::strerror(error));
  std::unique_ptr<RoudiProcess> roudi(new RoudiProcess(pid));
  const auto deadline = Clock::now() + kReadyTimeout;
  while (read_file(log_file).find(kReadyLine) == std::string::npos) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      roudi->pid_ = 0;
      throw std::runtime_error("image transport shm: iox-roudi -c " + config.string() + " exited at start (see " +
                               log_file.string() + ")");
    }
    if (Clock::now() > deadline) {
      throw std::runtime_error("image transport shm: iox-roudi did not say it is ready within " +
                               std::to_string(kReadyTimeout.count()) + " s (see " + log_file.string() + ")");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  log.info("image transport shm: started iox-roudi (pid ", pid, ") with ", config.string());
  return roudi;
}

RoudiProcess::~RoudiProcess() {
  if (pid_ <= 0) return;
  kill(pid_, SIGTERM);
  if (!wait_exit(pid_, kStopTimeout)) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
}

}  // namespace heslam::supervisor
