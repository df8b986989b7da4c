// What every plain benchmark program shares: the percentile of its samples and the main() that turns
// an exception into one line "PROGRAM: what" and exit code 1. Header-only; include as
// "tools/bench/bench_util.hpp".
#pragma once

#include <algorithm>
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace heslam::bench {

// The sample at `fraction` (0.5 = median, 1.0 = max) of `values`, nearest rank; 0 for none.
inline double percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(fraction * static_cast<double>(values.size() - 1) + 0.5);
  return values[std::min(index, values.size() - 1)];
}

// Calls handle(flag, value) for every "--flag value" pair of the command line. A flag without a
// value is an error naming it (with `usage`); so is a value std::sto* cannot parse (std::logic_error
// from `handle`). `handle` returns false for a flag it does not know.
template <typename Handle>
void for_each_flag(int argc, char** argv, const std::string& usage, Handle handle) {
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw std::runtime_error("missing value after " + flag + "\n" + usage);
    const std::string value = argv[++i];
    bool known = false;
    try {
      known = handle(flag, value);
    } catch (const std::logic_error&) {
      throw std::runtime_error("bad value '" + value + "' for " + flag);
    }
    if (!known) throw std::runtime_error("unknown option " + flag + "\n" + usage);
  }
}

// main() of a benchmark: run(argc, argv), any exception becomes one line on stderr and exit code 1.
template <typename Run>
int bench_main(const char* program, int argc, char** argv, Run run) {
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << program << ": " << error.what() << '\n';
    return 1;
  }
}

}  // namespace heslam::bench
