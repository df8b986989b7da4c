// The end of a watched or joined run, from the status topic (see run_end_watch.hpp).
#include "runtime/run_end_watch.hpp"

#include <cstdlib>

#include "runtime/run_id.hpp"
#include "runtime/run_self.hpp"
#include "runtime/sequence.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::runtime {
namespace {

// "supervisor" on one host, "supervisor@HOST" for each host of a multi-host run.
constexpr std::string_view kSupervisorName = "supervisor";
constexpr std::string_view kSupervisorExecutable = "heslam-supervisor";
constexpr std::string_view kReplayExecutable = "heslam-replay";

std::string_view base_name(std::string_view path) {
  const std::size_t slash = path.rfind('/');
  return slash == std::string_view::npos ? path : path.substr(slash + 1);
}

}  // namespace

bool RunEndRule::is_supervisor(std::string_view name, std::string_view executable) {
  return name == kSupervisorName || name.starts_with(std::string(kSupervisorName) + "@") ||
         base_name(executable) == kSupervisorExecutable;
}

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

void RunEndRule::supervisor_gone(std::string_view name) {
  if (!ended_) ended_ = "the supervisor (" + std::string(name) + ") is gone";
}

bool RunEndWatch::joined_by_hand() {
  const char* run = std::getenv(kJoinRunVariable);
  return run != nullptr && *run != '\0';
}

RunEndWatch::RunEndWatch(const Participant& participant, const Topics& topics)
    : reader_(participant, topics.status()), joined_(joined_by_hand()) {}

bool RunEndWatch::of_joined_run(dds_instance_handle_t writer) {
  if (joined_run_writers_.contains(writer)) return true;
  if (writer_run_id(reader_.handle(), writer).value_or("") != process_run_id()) return false;
  joined_run_writers_.insert(writer);
  return true;
}

std::optional<std::string> RunEndWatch::poll() {
  for (const auto& received : reader_.take()) {
    if (!received.info.valid_data) continue;
    const msg::ComponentStatus& status = *received.sample;
    const std::string name = to_string(status.name);
    const std::string executable = to_string(status.executable);
    const bool supervisor = RunEndRule::is_supervisor(name, executable);
    const dds_instance_handle_t writer = received.info.publication_handle;
    // Joined by hand: another run's supervisor (and its replay) on this domain is not ours.
    if (joined_ && !of_joined_run(writer)) continue;
    if (supervisor) {
      supervisor_writer_ = writer;
      supervisor_name_ = name;
    }
    rule_.observe(name, executable, status.state == heslam_msg_STATE_SHUTTING_DOWN);
  }
  if (!rule_.ended() && supervisor_writer_ && !writer_matched(reader_.handle(), *supervisor_writer_)) {
    rule_.supervisor_gone(supervisor_name_);
  }
  if (rule_.ended() && joined_) return *rule_.ended() + " (run " + process_run_id() + ")";
  return rule_.ended();
}

}  // namespace heslam::runtime
