// supervisor_run_id from /proc/<parent>/stat.
#include "runtime/run_id.hpp"

#include <unistd.h>

#include <fstream>
#include <iterator>
#include <sstream>

namespace heslam::runtime {
namespace {

// Field of /proc/<pid>/stat holding the process start time (proc(5)), counted from 1.
constexpr int kStatStartTimeField = 22;

}  // namespace

std::string supervisor_run_id() {
  const pid_t parent = getppid();
  std::ifstream stat("/proc/" + std::to_string(parent) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  // Fields counted after the ')' closing the command name, which may contain spaces.
  const std::size_t close = text.rfind(')');
  std::istringstream fields(close == std::string::npos ? std::string() : text.substr(close + 1));
  std::string field;
  for (int index = 3; index <= kStatStartTimeField && fields >> field; ++index) {}
  return std::to_string(parent) + ":" + field;
}

const std::string& process_run_id() {
  static const std::string run_id = supervisor_run_id();
  return run_id;
}

}  // namespace heslam::runtime
