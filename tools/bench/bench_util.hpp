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
