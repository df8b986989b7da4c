// Parsing heslam-spy's command line (one clear line per bad option).
#include "tools/spy/spy_options.hpp"

#include <limits>
#include <stdexcept>

#include "runtime/flags.hpp"

namespace heslam {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

runtime::Flags spy_flags(SpyOptions& options, std::vector<std::string>& positional) {
  runtime::Flags flags("heslam-spy list | echo TOPIC | hz TOPIC | bw TOPIC | info TOPIC [options]",
                       "  list          topics seen on the domain: type, writer and reader counts\n"
                       "  echo TOPIC    print samples (images summarised: size, stamp, mean intensity)\n"
                       "  hz TOPIC      rate with min/max/std of the period\n"
                       "  bw TOPIC      bytes per second and message sizes\n"
                       "  info TOPIC    QoS of every writer and reader, and incompatible pairs\n"
                       "  TOPIC is relative to the namespace (camera/stereo) or full (heslam/camera/stereo).");
  flags.toggle("--once", &options.once, "echo one sample / print one report, then exit")
      .integer("--count", "N", &options.count, std::size_t{1}, std::numeric_limits<std::size_t>::max(),
               "exit after N samples")
      .integer("--window", "N", &options.window, std::size_t{2}, std::numeric_limits<std::size_t>::max(),
               "hz/bw: statistics over the last N samples (100)")
      .toggle("--full", &options.full, "echo: every element, including image bytes")
      .number("--wait", "S", &options.wait_s, 0.0, kInfinity, "list/info: listen to discovery for S seconds (1)")
      .number("--timeout", "S", &options.timeout_s, 0.0, kInfinity,
              "echo/hz/bw: exit 1 when no sample arrives for S seconds (0 = wait forever)")
      .note("Spy readers are best effort, keep-last 1: tapping never slows the pipeline.")
      .positional("COMMAND", "", [&positional](const std::string& arg) { positional.push_back(arg); });
  return flags;
}

}  // namespace

std::string spy_usage() {
  SpyOptions unused;
  std::vector<std::string> unused_positional;
  return spy_flags(unused, unused_positional).usage();
}

SpyOptions parse_spy_options(const std::vector<std::string>& args) {
  SpyOptions options;
  std::vector<std::string> positional;
  spy_flags(options, positional).parse(args);
  if (positional.empty()) throw std::runtime_error("missing command: list, echo, hz, bw or info (see --help)");
  const std::string& command = positional[0];
  if (command == "list") {
    options.command = SpyCommand::kList;
  } else if (command == "echo") {
    options.command = SpyCommand::kEcho;
  } else if (command == "hz") {
    options.command = SpyCommand::kHz;
  } else if (command == "bw") {
    options.command = SpyCommand::kBw;
  } else if (command == "info") {
    options.command = SpyCommand::kInfo;
  } else {
    throw std::runtime_error("'" + command + "': unknown command (expected list, echo, hz, bw or info)");
  }
  const std::size_t wanted = options.command == SpyCommand::kList ? 1 : 2;
  if (positional.size() < wanted) throw std::runtime_error(command + ": missing TOPIC argument");
  if (positional.size() > wanted) throw std::runtime_error("'" + positional[wanted] + "': unexpected argument");
  if (wanted == 2) options.topic = positional[1];
  if (options.once && options.count == 0) options.count = options.command == SpyCommand::kEcho ? 1 : 0;
  return options;
}

}  // namespace heslam
