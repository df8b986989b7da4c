// The five heslam-spy commands (list, echo, hz, bw, info) on one participant.
#pragma once

#include "runtime/args.hpp"
#include "tools/spy/spy_options.hpp"

namespace heslam {

// Runs the command, printing to stdout. Returns the exit code (0 also on SIGINT); throws
// std::runtime_error with one line on errors (unknown topic, --timeout without a sample).
int run_spy(const runtime::CommonArgs& common, const SpyOptions& options);

}  // namespace heslam
