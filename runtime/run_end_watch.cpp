// The end of a watched run, from the status topic (see run_end_watch.hpp).
#include "runtime/run_end_watch.hpp"

#include "runtime/sequence.hpp"

namespace heslam::runtime {
namespace {

constexpr std::string_view kSupervisorName = "supervisor";
constexpr std::string_view kSupervisorExecutable = "heslam-supervisor";
constexpr std::string_view kReplayExecutable = "heslam-replay";

std::string_view base_name(std::string_view path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string_view::npos ? path : path.substr(slash + 1);
}

bool is_supervisor(std::string_view name, std::string_view executable) {
  return name == kSupervisorName || name.rfind(std::string(kSupervisorName) + "@", 0) == 0 ||
         base_name(executable) == kSupervisorExecutable;
}

}  // namespace

void RunEndRule::observe(std::string_view name, std::string_view executable, bool shutting_down) {
  if (ended_) return;
  if (is_supervisor(name, executable)) {
    supervisor_seen_ = true;
    if (shutting_down) ended_ = "the supervisor (" + std::string(name) + ") is ending the run";
    return;
  }
  if (!supervisor_seen_ && shutting_down && base_name(executable) == kReplayExecutable) {
    ended_ = "the replay (" + std::string(name) + ") finished and no supervisor runs";
  }
}

RunEndWatch::RunEndWatch(const Participant& participant, const Topics& topics)
    : reader_(participant, topics.status()) {}

bool RunEndWatch::poll() {
  for (const auto& received : reader_.take()) {
    if (!received.info.valid_data) continue;
    const msg::ComponentStatus& status = *received.sample;
    rule_.observe(to_string(status.name), to_string(status.executable), status.state == heslam_msg_STATE_SHUTTING_DOWN);
  }
  return rule_.ended().has_value();
}

}  // namespace heslam::runtime
