// Parsing heslam-spy's command line (one clear line per bad option).
#include "tools/spy/spy_options.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace heslam {

namespace {

double parse_seconds(const std::string& option, const std::string& text) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size() || !std::isfinite(value) || value < 0.0) {
    throw std::runtime_error(option + ": expected seconds >= 0, got '" + text + "'");
  }
  return value;
}

std::size_t parse_count(const std::string& option, const std::string& text, std::size_t min_value) {
  std::size_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size() || value < min_value) {
    throw std::runtime_error(option + ": expected an integer >= " + std::to_string(min_value) + ", got '" + text + "'");
  }
  return value;
}

}  // namespace

const char* spy_usage() {
  return "usage: heslam-spy list | echo TOPIC | hz TOPIC | bw TOPIC | info TOPIC [options]\n"
         "  list          topics seen on the domain: type, writer and reader counts\n"
         "  echo TOPIC    print samples (images summarised: size, stamp, mean intensity)\n"
         "  hz TOPIC      rate with min/max/std of the period\n"
         "  bw TOPIC      bytes per second and message sizes\n"
         "  info TOPIC    QoS of every writer and reader, and incompatible pairs\n"
         "  TOPIC is relative to the namespace (camera/stereo) or full (heslam/camera/stereo).\n"
         "  --once        echo one sample / print one report, then exit\n"
         "  --count N     exit after N samples\n"
         "  --window N    hz/bw: statistics over the last N samples (100)\n"
         "  --full        echo: every element, including image bytes\n"
         "  --wait S      list/info: listen to discovery for S seconds (1)\n"
         "  --timeout S   echo/hz/bw: exit 1 when no sample arrives for S seconds (0 = wait forever)\n"
         "  Spy readers are best effort, keep-last 1: tapping never slows the pipeline.\n";
}

SpyOptions parse_spy_options(const std::vector<std::string>& args) {
  SpyOptions options;
  std::vector<std::string> positional;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    auto value = [&]() -> const std::string& {
      if (i + 1 >= args.size()) throw std::runtime_error(arg + ": missing value");
      return args[++i];
    };
    if (arg == "--once") {
      options.once = true;
    } else if (arg == "--count") {
      options.count = parse_count(arg, value(), 1);
    } else if (arg == "--window") {
      options.window = parse_count(arg, value(), 2);
    } else if (arg == "--full") {
      options.full = true;
    } else if (arg == "--wait") {
      options.wait_s = parse_seconds(arg, value());
    } else if (arg == "--timeout") {
      options.timeout_s = parse_seconds(arg, value());
    } else if (!arg.empty() && arg.front() == '-') {
      throw std::runtime_error(arg + ": unknown option (see --help)");
    } else {
      positional.push_back(arg);
    }
  }
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
