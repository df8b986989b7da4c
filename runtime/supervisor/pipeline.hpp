// Pipeline: the parsed and validated pipeline file heslam-supervisor runs (format: docs/supervisor.md).
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "runtime/dds_network_profile.hpp"
#include "runtime/image_transport.hpp"

namespace heslam::supervisor {

enum class RestartPolicy { kNever, kOnFailure, kAlways };
enum class Readiness { kStatus, kStarted };

struct ComponentSpec {
  std::string name;                  // unique in the pipeline; also its --name and log file
  std::filesystem::path executable;  // resolved absolute path
  std::vector<std::string> args;     // after $(arg) substitution
  // --config files in order, each overlaying the ones before (field `config`: a file, or a list such
  // as [shipped.yaml, $(arg user_config)], empty entries skipped); empty: none.
  std::vector<std::filesystem::path> configs;
  // Files or folders it reads (e.g. the dataset): each must exist, checked by --check and before
  // anything starts, so a wrong path is one line and exit 1 instead of a failing, restarting process.
  std::vector<std::filesystem::path> inputs;
  std::map<std::string, std::string> env;  // added to the supervisor's environment
  RestartPolicy restart = RestartPolicy::kNever;
  int max_restarts = 3;            // restarts allowed before giving up
  double restart_backoff_s = 0.1;  // first delay; doubles per consecutive restart
  double restart_backoff_max_s = 5.0;
  Readiness ready = Readiness::kStatus;  // status: the next component waits for this one's status
  // after: the components (earlier in the file) whose readiness this one's start waits for; unset:
  // the previous component (one after the other); empty: none, it starts with the supervisor. Names of
  // disabled components are kept here and skipped by the supervisor.
  std::optional<std::vector<std::string>> after;
  double ready_timeout_s = 10.0;
  // SIGTERM -> SIGKILL for this process; unset: the pipeline's stop_timeout_s (a process with long
  // shutdown work, e.g. heslam-occupancy's final fusion, gets its own without slowing the others').
  std::optional<double> stop_timeout_s;
  bool required = true;           // its failure fails the run (exit code 1)
  bool shutdown_on_exit = false;  // on_exit: shutdown — its end ends the run
  // on_exit: shutdown_with_all — the run ends when every component with this choice has ended (the
  // replays of several agents, docs/agents.md)
  bool shutdown_with_all = false;
  bool common_args = true;  // pass --domain --namespace --name [--config] --log-level --dds-config
  // pausable: true — space on the supervisor's terminal pauses it (SIGUSR1) and resumes it (SIGUSR2),
  // as heslam-replay's own keyboard would (docs/supervisor.md, Pause).
  bool pausable = false;
  // Added to the supervisor's own niceness for this process and all its threads (0-19): a real-time
  // pipeline puts the mapper and the loop closer below the frontend, whose frames have a deadline.
  int nice = 0;
  // Runs on another host (hosts: groups, --host / --only): never started, stopped or restarted here;
  // its readiness is read from the status topic (docs/deployment.md).
  bool remote = false;
  // DDS Security identity in a secure pipeline (SECURITY_DIR/identities/IDENTITY, given to the process
  // as $HESLAM_SECURITY); default: the component's name. Unused in a plain pipeline.
  std::string identity;
};

struct Pipeline {
  std::filesystem::path file;
  std::string name;  // default: file stem
  int domain_id = 0;
  std::string ns = "heslam";
  std::string dds_config;  // "file://ABS" or "" (built-in loopback XML)
  // Secure mode: the folder made by heslam-security init (absolute); empty: plain DDS. The
  // supervisor runs as identity "supervisor", each component as its own (docs/security.md).
  std::filesystem::path security_dir;
  // image_transport: udp (default) or shm — the stereo images over iceoryx shared memory on domain
  // image_domain (default: domain + 1, or domain - 1 on the last id), every other topic stays on UDP.
  // The supervisor uses a running iox-roudi or starts one with roudi_config (docs/topics.md).
  runtime::ImageTransport image_transport = runtime::ImageTransport::kUdp;
  int image_domain_id = -1;
  std::filesystem::path roudi_config;     // default: FOLDER/../iceoryx/roudi.toml (config/iceoryx/)
  double stop_timeout_s = 5.0;            // SIGTERM -> SIGKILL
  std::vector<ComponentSpec> components;  // start order
  // Components whose executable is "none" (e.g. --arg loop_closer=none): validated, not started.
  std::vector<std::string> disabled_components;
  // dds_profile: network — the processes talk over this interface (the XML is written into the log
  // folder at start and passed like dds_config). nullopt: loopback (or dds_config).
  std::optional<runtime::DdsNetworkProfile> network;
  // Multi-host runs (docs/deployment.md): this supervisor's host (--host, else empty), the host
  // groups of the file (hosts:, group name -> component names), and how long to wait for a component
  // of another host to say RUNNING before starting the next one anyway.
  std::string host;
  std::map<std::string, std::vector<std::string>> hosts;
  double remote_ready_timeout_s = 120.0;
  bool split() const {
    for (const auto& component : components) {
      if (component.remote) return true;
    }
    return false;
  }
};

// The executable value that disables a component.
inline constexpr const char* kDisabledExecutable = "none";

struct PipelineOverrides {
  std::map<std::string, std::string> args;  // --arg key=value
  std::optional<int> domain_id;
  std::optional<std::string> ns;
  std::string host;                            // --host NAME: run the components of the file's hosts.NAME group
  std::vector<std::string> only;               // --only a,b: run only these components (the others run elsewhere)
  std::optional<std::string> security_dir;     // --security DIR ("" = plain even if the file says otherwise)
  std::optional<std::string> image_transport;  // --image-transport udp|shm
  std::optional<int> image_domain_id;          // --image-domain N
};

// The identity the supervisor itself runs as in a secure pipeline.
inline constexpr const char* kSupervisorIdentity = "supervisor";

// Loads and validates. Problems are collected, one line each ("FILE: ..."); the pipeline is only
// usable when problems is empty. bin_dir is searched first for executables, then $PATH.
struct LoadResult {
  Pipeline pipeline;
  std::vector<std::string> problems;
};
LoadResult load_pipeline(const std::filesystem::path& file, const PipelineOverrides& overrides,
                         const std::filesystem::path& bin_dir);

// The arguments with the $(arg NAME) / $(stem NAME) in their values replaced by the other
// arguments' (an argument may default to another's); a cycle, or a chain deeper than 16, is one
// problem naming the arguments involved.
std::map<std::string, std::string> resolve_args(const std::map<std::string, std::string>& args,
                                                const std::string& source, std::vector<std::string>& problems);

// Replaces every $(arg NAME), and $(stem NAME) by the value without its extension (a/run.txt ->
// a/run: the outputs of a run are named OUTPUT stem + .map, .loop, ...); unknown names are reported
// in unknown.
std::string substitute_args(const std::string& text, const std::map<std::string, std::string>& args,
                            std::vector<std::string>& unknown);

}  // namespace heslam::supervisor
