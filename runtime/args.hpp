// The command-line flags every component and tool shares (the pipeline file sets them):
//   --domain N  --namespace NAME  --agent-namespace NAME  --name NAME  --config FILE  --log-level LEVEL  --dds-config
//   XML|file://…
//   --image-transport udp|shm  --image-domain N  --check
// parse_common_args() takes these out and leaves every other argument, in order, for the tool.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/image_transport.hpp"
#include "runtime/log.hpp"

namespace heslam::runtime {

struct CommonArgs {
  int domain_id = 0;          // default: $HESLAM_DOMAIN when set, else 0
  std::string ns = "heslam";  // topic namespace
  // --agent-namespace NAME: this process belongs to one agent of several (docs/agents.md): its
  // frames, IMU, odometry and FrameDone topics go under NS/NAME/, the map topics stay shared. Empty:
  // a single agent, every topic directly under NS.
  std::string agent_ns;
  std::string name;     // instance name (status key, log prefix); default: the program's
  std::string program;  // the executable's name for error lines, see program_name()
  // --config, in order: each file overlays the ones before it field by field (the pipeline passes its
  // shipped file, then a user's); none: every option at its documented default.
  std::vector<std::filesystem::path> config_files;
  LogLevel log_level = LogLevel::kInfo;
  std::string dds_config;  // empty: see ParticipantOptions::dds_config
  // The stereo image topic: UDP on domain_id, or iceoryx shared memory on image_domain_id (required
  // then, and different from domain_id; runtime/image_transport.hpp).
  ImageTransport image_transport = ImageTransport::kUdp;
  int image_domain_id = -1;
  bool help = false;              // -h / --help seen
  bool check = false;             // --check: validate the arguments and the config, start nothing
  std::vector<std::string> rest;  // everything else, in order (argv[0] excluded)
};

// Accepts "--flag value" and "--flag=value". Throws std::runtime_error with one line for a bad value,
// e.g. "--domain: expected an integer in [0, 232], got 'x'".
CommonArgs parse_common_args(int argc, const char* const* argv, std::string_view default_name);

// The name a user typed, for "<program>: <what>" lines: the file name of argv[0] when it is a
// heslam executable (heslam-local-mapper), else "heslam-" + default_name with '_' as '-'.
std::string program_name(const char* argv0, std::string_view default_name);

// The help text of the common flags (append to a tool's own usage).
std::string common_args_usage();

}  // namespace heslam::runtime
