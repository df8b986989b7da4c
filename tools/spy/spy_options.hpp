// heslam-spy's own command line (after runtime::parse_common_args took --domain, --namespace, ...).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace heslam {

enum class SpyCommand { kList, kEcho, kHz, kBw, kInfo };

struct SpyOptions {
  SpyCommand command = SpyCommand::kList;
  std::string topic;         // echo / hz / bw / info: full ("heslam/camera/stereo") or relative name
  bool once = false;         // echo: one sample; hz / bw: one report
  std::size_t count = 0;     // stop after this many samples (0 = until Ctrl-C)
  std::size_t window = 100;  // hz / bw: samples the statistics cover
  bool full = false;         // echo: every element, image bytes included
  double wait_s = 1.0;       // list / info: how long to listen to discovery
  double timeout_s = 0.0;    // echo / hz / bw: fail when nothing arrives for this long (0 = never)
};

// Throws std::runtime_error naming the option and what was expected.
SpyOptions parse_spy_options(const std::vector<std::string>& args);

std::string spy_usage();

}  // namespace heslam
