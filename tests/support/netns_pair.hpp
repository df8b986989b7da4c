// Two test "hosts" on one machine: network namespaces joined by a veth pair, each end with its own
// address (made by the test, nothing outside the machine), removed when the object goes. Needs root
// and `ip netns`; available() says why not, for a GTEST_SKIP.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "child_process.hpp"

namespace heslam::test {

class NetnsPair {
 public:
  // Names carry this prefix and the test process's pid: unique per test process, and a namespace
  // left by a killed test (a ctest timeout skips destructors) is recognised and removed by the next.
  static constexpr const char* kPrefix = "hslt";
  static constexpr const char* kInterface = "hsnet0";

  // Why two namespaces cannot be made here (not root, no `ip`, netns refused), or nullopt.
  static std::optional<std::string> unavailable() {
    if (geteuid() != 0) return "needs root to create network namespaces (ip netns); run as root to test multi-host";
    if (ip_path().empty()) return "needs the `ip` command (iproute2) for network namespaces";
    const std::string probe = std::string(kPrefix) + "probe" + std::to_string(getpid());
    if (!run(ip_path() + " netns add " + probe))
      return "`ip netns add` failed here (a container without CAP_SYS_ADMIN?)";
    run(ip_path() + " netns del " + probe);
    return std::nullopt;
  }

  NetnsPair() {
    remove_stale();
    const std::string id = std::to_string(getpid());
    ns_[0] = std::string(kPrefix) + id + "a";
    ns_[1] = std::string(kPrefix) + id + "b";
    veth_[0] = "hv" + id + "a";  // interface names: at most 15 characters
    veth_[1] = "hv" + id + "b";
    root_veth_ = veth_[0];
    // Each namespace has its own stack, so fixed addresses cannot collide with another test's.
    address_[0] = "10.213.7.1";
    address_[1] = "10.213.7.2";
    const std::string ip = ip_path();
    ok_ = run(ip + " netns add " + ns_[0]) && run(ip + " netns add " + ns_[1]) &&
          run(ip + " link add " + veth_[0] + " type veth peer name " + veth_[1]) &&
          run(ip + " link set " + veth_[0] + " netns " + ns_[0]) &&
          run(ip + " link set " + veth_[1] + " netns " + ns_[1]);
    // Both ends get the same name inside their namespace, as two real hosts both have "eth0": one
    // dds_interface works for both halves of a pipeline.
    for (int i = 0; i < 2 && ok_; ++i) {
      ok_ = exec(i, "ip link set " + veth_[i] + " name " + std::string(kInterface));
      if (ok_) veth_[i] = kInterface;
    }
    for (int i = 0; i < 2 && ok_; ++i) {
      ok_ = exec(i, "ip addr add " + address_[i] + "/24 dev " + veth_[i]) &&
            exec(i, "ip link set " + veth_[i] + " up") && exec(i, "ip link set lo up");
    }
  }
  ~NetnsPair() {
    run(ip_path() + " netns del " + ns_[0]);
    run(ip_path() + " netns del " + ns_[1]);
    run(ip_path() + " link del " + root_veth_);  // only if it never made it into a namespace
  }
  NetnsPair(const NetnsPair&) = delete;
  NetnsPair& operator=(const NetnsPair&) = delete;

  bool ok() const { return ok_; }
  const std::string& ns(int host) const { return ns_[host]; }
  const std::string& interface(int host) const { return veth_[host]; }
  const std::string& address(int host) const { return address_[host]; }
  std::string peers() const { return address_[0] + "," + address_[1]; }

  // Runs a shell command inside host's namespace; true on exit code 0.
  bool exec(int host, const std::string& command) const {
    return run(ip_path() + " netns exec " + ns_[host] + " " + command);
  }
  // The link between the hosts down or up (both ends, as a pulled cable).
  bool set_link(bool up) const {
    const std::string state = up ? " up" : " down";
    return exec(0, "ip link set " + veth_[0] + state) && exec(1, "ip link set " + veth_[1] + state);
  }
  // program with args inside host's namespace (`ip netns exec` execs it: the pid is the program's).
  std::unique_ptr<ChildProcess> spawn(int host, const std::filesystem::path& program,
                                      const std::vector<std::string>& args, const std::filesystem::path& log_dir,
                                      const std::string& label) const {
    std::vector<std::string> all{"netns", "exec", ns_[host], program.string()};
    all.insert(all.end(), args.begin(), args.end());
    return std::make_unique<ChildProcess>(ip_path(), all, log_dir, label);
  }

  static std::string ip_path() {
    for (const char* path : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"}) {
      if (access(path, X_OK) == 0) return path;
    }
    return "";
  }

 private:
  static bool run(const std::string& command) { return std::system((command + " >/dev/null 2>&1").c_str()) == 0; }

  // Namespaces of test processes that no longer exist (killed before their destructor ran).
  static void remove_stale() {
    const std::filesystem::path dir = "/var/run/netns";
    std::error_code error;
    if (!std::filesystem::is_directory(dir, error)) return;
    for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind(kPrefix, 0) != 0 || name.size() < std::string(kPrefix).size() + 2) continue;
      const std::string digits =
          name.substr(std::string(kPrefix).size(), name.size() - std::string(kPrefix).size() - 1);
      if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) continue;
      const pid_t pid = std::stoi(digits);
      if (kill(pid, 0) != 0 && errno == ESRCH) run(ip_path() + " netns del " + name);
    }
  }

  std::string ns_[2], veth_[2], address_[2], root_veth_;
  bool ok_ = false;
};

// Stops the runs still going when the test leaves early (a failed ASSERT): SIGTERM to each
// supervisor, which stops its components, and a bounded wait; ChildProcess's own destructor would
// SIGKILL the supervisor, and the namespaces are deleted right after, so a component still shutting
// down then loses its network interface and hangs for good in Cyclone's dds_delete (its receive
// thread is never woken). Declared after the runs, so it runs before their destructors.
class StopRunsOnExit {
 public:
  explicit StopRunsOnExit(std::vector<ChildProcess*> runs) : runs_(std::move(runs)) {}
  ~StopRunsOnExit() {
    for (ChildProcess* run : runs_) run->signal(SIGTERM);
    for (ChildProcess* run : runs_) run->wait(kStopBound);
  }
  StopRunsOnExit(const StopRunsOnExit&) = delete;
  StopRunsOnExit& operator=(const StopRunsOnExit&) = delete;

 private:
  // A supervisor gives its components a few seconds after SIGTERM; this leaves room on a loaded machine.
  static constexpr std::chrono::seconds kStopBound{60};
  std::vector<ChildProcess*> runs_;
};

}  // namespace heslam::test
