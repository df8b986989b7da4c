// supervisor_run_id from /proc/<parent>/stat.
#include "runtime/run_id.hpp"

#include "runtime/run_self.hpp"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

namespace heslam::runtime {
namespace {

// Field of /proc/<pid>/stat holding the process start time (proc(5)), counted from 1.
constexpr int kStatStartTimeField = 22;

bool g_own_run_adopted = false;  // heslam-supervisor: process_run_id() is its own

// "<pid>:<start time>" of process `pid` (empty start time when it cannot be read).
std::string run_id_of(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  // Fields counted after the ')' closing the command name, which may contain spaces.
  const std::size_t close = text.rfind(')');
  std::istringstream fields(close == std::string::npos ? std::string() : text.substr(close + 1));
  std::string field;
  for (int index = 3; index <= kStatStartTimeField && fields >> field; ++index) {
  }
  return std::to_string(pid) + ":" + field;
}

}  // namespace

std::string supervisor_run_id() { return run_id_of(getppid()); }

std::string own_run_id() { return run_id_of(getpid()); }

bool run_on_one_host() {
  const char* value = std::getenv(kRunOnOneHostVariable);
  return value != nullptr && std::string_view(value) == "1";
}

void adopt_own_run_id() {
  g_own_run_adopted = true;
  unsetenv(kJoinRunVariable);
}

const std::string& process_run_id() {
  static const std::string run_id = [] {
    if (g_own_run_adopted) return own_run_id();
    const char* joined = std::getenv(kJoinRunVariable);
    return joined != nullptr && *joined != '\0' ? std::string(joined) : supervisor_run_id();
  }();
  return run_id;
}

}  // namespace heslam::runtime
