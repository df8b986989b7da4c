// Parsing of the flags every heslam process shares.
#include "runtime/args.hpp"

#include <algorithm>
#include <charconv>
#include <optional>
#include <cstdlib>
#include <stdexcept>

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

CommonArgs parse_common_args(int argc, const char* const* argv, std::string_view default_name) {
  CommonArgs args;
  args.name = std::string(default_name);
  args.program = program_name(argc > 0 ? argv[0] : nullptr, default_name);
  if (const char* env = std::getenv("HESLAM_DOMAIN"); env != nullptr && *env != '\0') {
    args.domain_id = parse_domain("$HESLAM_DOMAIN", env);
  }
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    std::string flag = arg;
    std::optional<std::string> inline_value;
    if (arg.rfind("--", 0) == 0) {
      if (const auto eq = arg.find('='); eq != std::string::npos) {
        flag = arg.substr(0, eq);
        inline_value = arg.substr(eq + 1);
      }
    }
    const auto value = [&]() -> std::string {
      if (inline_value) return *inline_value;
      if (i + 1 >= argc) throw std::runtime_error(flag + ": missing value");
      return argv[++i];
    };
    if (flag == "--domain") {
      args.domain_id = parse_domain(flag, value());
    } else if (flag == "--namespace") {
      args.ns = value();
      Topics check(args.ns);  // throws the namespace message
    } else if (flag == "--name") {
      args.name = value();
      if (args.name.empty()) throw std::runtime_error("--name: expected a non-empty name");
    } else if (flag == "--config") {
      args.config_files.push_back(value());
    } else if (flag == "--log-level") {
      const std::string text = value();
      const auto level = parse_log_level(text);
      if (!level) {
        throw std::runtime_error("--log-level: expected debug, info, warn, error or off, got '" + quote_value(text) + "'");
      }
      args.log_level = *level;
    } else if (flag == "--dds-config") {
      args.dds_config = value();
    } else if (flag == "--image-transport") {
      const std::string text = value();
      const auto transport = parse_image_transport(text);
      if (!transport) throw std::runtime_error("--image-transport: expected udp or shm, got '" + quote_value(text) + "'");
      args.image_transport = *transport;
    } else if (flag == "--image-domain") {
      args.image_domain_id = parse_domain(flag, value());
    } else if (arg == "-h" || arg == "--help") {
      args.help = true;
    } else if (arg == "--check") {
      args.check = true;
    } else {
      args.rest.push_back(arg);
    }
  }
  if (args.image_transport == ImageTransport::kShm &&
      (args.image_domain_id < 0 || args.image_domain_id == args.domain_id)) {
    throw std::runtime_error("--image-transport shm: needs --image-domain N, a domain other than --domain (" +
                             std::to_string(args.domain_id) + ")");
  }
  return args;
}

std::string common_args_usage() {
  return "common options:\n"
         "  --domain N          DDS domain id, 0-232 (default: $HESLAM_DOMAIN or 0)\n"
         "  --namespace NAME    topic namespace (default: heslam)\n"
         "  --name NAME         instance name in status and logs (default: the program's)\n"
         "  --config FILE       YAML options (default: every option at its documented default); given\n"
         "                      again, the later file overlays the earlier one field by field\n"
         "  --log-level LEVEL   debug, info, warn, error or off (default: info)\n"
         "  --dds-config XML    Cyclone configuration, XML or file://PATH (default: $CYCLONEDDS_URI,\n"
         "                      else the built-in loopback config/cyclonedds.xml)\n"
         "  --image-transport T udp (default) or shm: the stereo images over iceoryx shared memory on\n"
         "                      --image-domain N (replay, frontend, viewer; needs iox-roudi; docs/topics.md)\n"
         "  --check             check the arguments and the config file, start nothing (exit code 0: a\n"
         "                      run would accept them; heslam-supervisor --check runs this for each program)\n"
         "  -h, --help          this help\n";
}

}  // namespace heslam::runtime
