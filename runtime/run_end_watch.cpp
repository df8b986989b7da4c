// Watching the run's supervisor from a process that joined it by hand (runtime/run_end_watch.hpp).
#include "runtime/run_end_watch.hpp"

#include <cstdlib>

#include "runtime/run_id.hpp"
#include "runtime/run_self.hpp"
#include "runtime/sequence.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::runtime {
namespace {

// "supervisor" on one host, "supervisor@HOST" for each host of a multi-host run.
constexpr std::string_view kSupervisorStatusName = "supervisor";

}  // namespace

bool RunEndWatch::joined_by_hand() {
  const char* run = std::getenv(kJoinRunVariable);
  return run != nullptr && *run != '\0';
}

RunEndWatch::RunEndWatch(const Participant& participant, const Topics& topics)
    : reader_(participant, topics.status()) {}

std::optional<std::string> RunEndWatch::poll() {
  for (auto& received : reader_.take()) {
    if (!received.info.valid_data) continue;
    const std::string name = to_string(received.sample->name);
    if (!name.starts_with(kSupervisorStatusName)) continue;
    const dds_instance_handle_t writer = received.info.publication_handle;
    if (writer_run_id(reader_.handle(), writer).value_or("") != process_run_id()) continue;
    supervisor_writer_ = writer;
    supervisor_name_ = name;
    if (received.sample->state == heslam_msg_STATE_SHUTTING_DOWN) {
      return "the run's " + name + " is ending the run " + process_run_id();
    }
  }
  if (supervisor_writer_ && !writer_matched(reader_.handle(), *supervisor_writer_)) {
    return "the run's " + supervisor_name_ + " is gone (run " + process_run_id() + ")";
  }
  return std::nullopt;
}

}  // namespace heslam::runtime
