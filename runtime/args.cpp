// Parsing of the flags every heslam process shares.
#include "runtime/args.hpp"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <stdexcept>

#include "runtime/flags.hpp"
#include "runtime/participant.hpp"
#include "runtime/quote_value.hpp"
#include "runtime/topics.hpp"

namespace heslam::runtime {
namespace {

int parse_domain(const std::string& flag, const std::string& text) {
  int value = -1;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size() || value < 0 || value > kMaxDomainId) {
    throw std::runtime_error(flag + ": expected an integer in [0, " + std::to_string(kMaxDomainId) + "], got '" +
                             quote_value(text) + "'");
  }
  return value;
}

}  // namespace

std::string program_name(const char* argv0, std::string_view default_name) {
  if (argv0 != nullptr) {
    const std::string file = std::filesystem::path(argv0).filename().string();
    if (file.rfind("heslam-", 0) == 0) return file;
  }
  std::string program = "heslam-" + std::string(default_name);
  std::replace(program.begin(), program.end(), '_', '-');
  return program;
}

namespace {

// The common flags, declared once for the parser and the usage.
Flags common_flags(CommonArgs& args) {
  Flags flags("[options]");
  const std::string domain_range = "0-" + std::to_string(kMaxDomainId);
  flags
      .integer("--domain", "N", &args.domain_id, 0, kMaxDomainId,
               "DDS domain id, " + domain_range + " (default: $HESLAM_DOMAIN or 0)")
      .custom("--namespace", "NAME", "topic namespace (default: heslam)",
              [&args](const std::string& value) {
                Topics check(value);  // throws the namespace message
                args.ns = value;
              })
      .custom("--agent-namespace", "NAME",
              "one agent of several (docs/agents.md): its frames, IMU, odometry and FrameDone\n"
              "under NAMESPACE/NAME/ (default: none, a single agent)",
              [&args](const std::string& value) {
                Topics check(args.ns, value);  // throws the namespace message
                args.agent_ns = value;
              })
      .non_empty_text("--name", "NAME", &args.name, "instance name in status and logs (default: the program's)")
      .custom("--config", "FILE",
              "YAML options (default: every option at its documented default); given\n"
              "again, the later file overlays the earlier one field by field",
              [&args](const std::string& value) { args.config_files.emplace_back(value); })
      .custom("--log-level", "LEVEL", "debug, info, warn, error or off (default: info)",
              [&args](const std::string& value) {
                const auto level = parse_log_level(value);
                if (!level) throw_bad_flag_value("--log-level", "debug, info, warn, error or off", value);
                args.log_level = *level;
              })
      .text("--dds-config", "XML", &args.dds_config,
            "Cyclone configuration, XML or file://PATH (default: $CYCLONEDDS_URI,\n"
            "else the built-in loopback config/cyclonedds.xml)")
      .custom("--image-transport", "T",
              "udp (default) or shm: the stereo images over iceoryx shared memory on\n"
              "--image-domain N (replay, frontend, viewer; needs iox-roudi; docs/topics.md)",
              [&args](const std::string& value) {
                const auto transport = parse_image_transport(value);
                if (!transport) throw_bad_flag_value("--image-transport", "udp or shm", value);
                args.image_transport = *transport;
              })
      .integer("--image-domain", "N", &args.image_domain_id, 0, kMaxDomainId,
               "the DDS domain of the shm image topic, " + domain_range)
      .toggle("--check", &args.check,
              "check the arguments and the config file, start nothing (exit code 0: a\n"
              "run would accept them; heslam-supervisor --check runs this for each program)")
      .toggle("--help", &args.help, "this help")
      .alias("-h");
  return flags;
}

}  // namespace

CommonArgs parse_common_args(int argc, const char* const* argv, std::string_view default_name) {
  CommonArgs args;
  args.name = std::string(default_name);
  args.program = program_name(argc > 0 ? argv[0] : nullptr, default_name);
  if (const char* env = std::getenv("HESLAM_DOMAIN"); env != nullptr && *env != '\0') {
    args.domain_id = parse_domain("$HESLAM_DOMAIN", env);
  }
  args.rest = common_flags(args).parse(argc, argv, Flags::Unknown::kKeep);
  if (args.image_transport == ImageTransport::kShm &&
      (args.image_domain_id < 0 || args.image_domain_id == args.domain_id)) {
    throw std::runtime_error("--image-transport shm: needs --image-domain N, a domain other than --domain (" +
                             std::to_string(args.domain_id) + ")");
  }
  return args;
}

std::string common_args_usage() {
  CommonArgs unused;
  return "common options:\n" + common_flags(unused).flag_lines();
}

}  // namespace heslam::runtime
