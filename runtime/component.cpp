// Component lifecycle: configure -> run -> shutdown, with status and one-line errors.
#include "runtime/component.hpp"

#include <iostream>

namespace heslam::runtime {

Component::Component(std::string default_name, const CommonArgs& args)
    : program_(args.program.empty() ? program_name(nullptr, default_name) : args.program),
      name_(args.name.empty() ? default_name : args.name),
      args_(args),
      log_(name_, args.log_level),
      participant_(ParticipantOptions{args.domain_id, args.dds_config}),
      image_participant_(participant_, args.image_transport, args.image_domain_id, args.dds_config),
      topics_(args.ns, args.agent_ns),
      status_(std::make_unique<StatusPublisher>(participant_, topics_, name_, stats_)),
      waitset_(participant_) {
  install_shutdown_handlers();
}

Component::~Component() = default;

int Component::execute() {
  try {
    if (!args_.rest.empty() && !accepts_positional_args()) {
      throw std::runtime_error("unexpected argument '" + args_.rest.front() + "' (see --help)");
    }
    const Config config = Config::load(args_.config_files);
    configure(config);
    config.reject_unknown();
    status_->set_state(ComponentState::kRunning);
    log_.debug("running on domain ", participant_.domain_id(), ", namespace '", topics_.ns(), "'");
    run();
    status_->set_state(ComponentState::kShuttingDown);
    on_shutdown();
    log_.flush_throttled();
    return 0;
  } catch (const std::exception& error) {
    log_.flush_throttled();
    std::cerr << program_ << ": " << error.what() << std::endl;
    try {
      status_->set_state(ComponentState::kFailed, error.what());
    } catch (...) {
      // Reporting the failure failed too (DDS gone); the exit code still says it.
    }
    return 1;
  }
}

void Component::spin() {
  while (spin_once(std::chrono::milliseconds(kSpinTimeoutMs))) {
  }
}

bool Component::spin_once(std::chrono::milliseconds timeout) {
  log_.flush_throttled(/*due_only=*/true);
  const Wake wake = waitset_.wait(timeout);
  if (wake == Wake::kShutdown) return false;
  if (wake == Wake::kData) {
    for (const auto& subscription : subscriptions_) subscription->dispatch();
  }
  return !shutdown_requested();
}

}  // namespace heslam::runtime
