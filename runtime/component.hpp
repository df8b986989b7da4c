// Component: the base of every heslam process (like an rclcpp component).
//
//   class Frontend : public runtime::Component {
//    public:
//     explicit Frontend(const runtime::CommonArgs& args) : Component("frontend", args) {}
//    private:
//     void configure(const runtime::Config& config) override { ... read options, make readers/writers }
//     void run() override { ... loop until shutdown_requested(), or call spin() }
//   };
//   int main(int argc, char** argv) { return runtime::component_main<Frontend>(argc, argv, "frontend"); }
//
// Lifecycle: construct (participant, status "configuring") -> configure(config) (unknown fields are
// errors) -> status "running" -> run() -> on_shutdown() -> status gone. Exceptions end the process
// with one line "<program>: <what>" on stderr (the executable's name, e.g. heslam-local-mapper), status FAILED and exit
// code 1; SIGINT/SIGTERM end run() cleanly (exit 0).
#pragma once

#include <chrono>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "runtime/args.hpp"
#include "runtime/config.hpp"
#include "runtime/image_transport.hpp"
#include "runtime/log.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/stats.hpp"
#include "runtime/status.hpp"
#include "runtime/topics.hpp"
#include "runtime/waitset.hpp"
#include "runtime/writer.hpp"

namespace heslam::runtime {

class Component {
 public:
  Component(std::string default_name, const CommonArgs& args);
  virtual ~Component();
  Component(const Component&) = delete;
  Component& operator=(const Component&) = delete;

  // configure -> run -> shutdown; returns the process exit code (0 ok, 1 error).
  int execute();

 protected:
  virtual void configure(const Config& config) = 0;
  // Default: spin() until shutdown.
  virtual void run() { spin(); }
  virtual void on_shutdown() {}
  // Positional arguments (args().rest) are an error unless a component says it takes them.
  virtual bool accepts_positional_args() const { return false; }

  // Calls handler for every sample of the topic from spin() (in arrival order per topic).
  // handler: any callable taking Received<T>& (a lambda is fine).
  template <Message T, typename Handler>
  void subscribe(const TopicSpec<T>& spec, Handler&& handler) {
    auto sub = std::make_unique<Subscription<T>>(participant_, spec,
                                                 std::function<void(Received<T>&)>(std::forward<Handler>(handler)));
    waitset_.attach(sub->reader);
    subscriptions_.push_back(std::move(sub));
  }
  // Waits and dispatches subscriptions until shutdown is requested.
  void spin();
  // One round: waits up to timeout, dispatches what arrived; false once shutdown is requested.
  bool spin_once(std::chrono::milliseconds timeout);

  bool shutdown_requested() const { return runtime::shutdown_requested(); }

  const std::string& name() const { return name_; }
  const CommonArgs& args() const { return args_; }
  Participant& participant() { return participant_; }
  // The participant of the stereo image topic (--image-transport): participant() for UDP, else a
  // second one on the shared-memory image domain, created on first use (throws when iox-roudi is down).
  ImageParticipant& image_participant() { return image_participant_; }
  const Topics& topics() const { return topics_; }
  const Logger& log() const { return log_; }
  Stats& stats() { return stats_; }
  StatusPublisher& status() { return *status_; }

 private:
  struct SubscriptionBase {
    virtual ~SubscriptionBase() = default;
    virtual void dispatch() = 0;
  };
  template <Message T>
  struct Subscription : SubscriptionBase {
    Subscription(const Participant& participant, const TopicSpec<T>& spec, std::function<void(Received<T>&)> h)
        : reader(participant, spec), handler(std::move(h)) {}
    void dispatch() override {
      for (auto& received : reader.take()) handler(received);
    }
    Reader<T> reader;
    std::function<void(Received<T>&)> handler;
  };

  // spin() re-checks for shutdown at least this often even if a wake-up were missed.
  static constexpr int kSpinTimeoutMs = 200;

  std::string program_;  // the executable's name, the prefix of fatal errors
  std::string name_;
  CommonArgs args_;
  Logger log_;
  Participant participant_;
  ImageParticipant image_participant_;
  Topics topics_;
  Stats stats_;
  std::unique_ptr<StatusPublisher> status_;
  WaitSet waitset_;
  std::vector<std::unique_ptr<SubscriptionBase>> subscriptions_;
};

// Parses the common flags (prints usage for --help, then C::help_notes() when C has one),
// constructs C(args), executes it; with --check
// only loads the config and calls C::check(args, config) when C has one. Any exception
// becomes "<program>: <what>" on stderr and exit code 1.
template <typename C>
int component_main(int argc, char** argv, std::string_view default_name) {
  try {
    install_shutdown_handlers();
    const CommonArgs args = parse_common_args(argc, argv, default_name);
    if (args.help) {
      std::cout << "usage: " << args.program << " [options]\n" << common_args_usage();
      // A component's own topics and config fields, when it lists them (static std::string help_notes()).
      if constexpr (requires { C::help_notes(); }) std::cout << C::help_notes();
      return 0;
    }
    if (args.check) {
      // What a run would refuse at start-up, without DDS or files written: the config file's syntax
      // and, for a component that has one, its own check of its flags and fields.
      const Config config = Config::load(args.config_files);
      if constexpr (requires { C::check(args, config); }) C::check(args, config);
      return 0;
    }
    C component(args);
    return component.execute();
  } catch (const std::exception& error) {
    std::cerr << program_name(argc > 0 ? argv[0] : nullptr, default_name) << ": " << error.what() << "\n";
    return 1;
  }
}

}  // namespace heslam::runtime
