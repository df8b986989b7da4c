// How far a lockstep run is, read from a journal a component keeps while it runs: the recorder's (OUTPUT stem +
// .journal) and the frontend's (+ .frontend, per agent + .a.frontend ...) survive a restart of their process and
// are removed at the end of the run. The recovery tests time their kills by it (progress, not wall time).
#pragma once

#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace heslam::test {

// Frames a journal holds: one more than the largest seq at the start of a line after its header.
inline std::size_t frames_in_journal(const std::filesystem::path& journal) {
  std::ifstream in(journal);
  std::string line;
  std::getline(in, line);  // header
  std::size_t frames = 0;
  unsigned long long seq = 0;
  while (std::getline(in, line)) {
    if (std::istringstream(line) >> seq) frames = std::max<std::size_t>(frames, seq + 1);
  }
  return frames;
}

}  // namespace heslam::test
