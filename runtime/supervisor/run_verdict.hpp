// The verdict of a run from what its programs reported as they ended (runtime/run_counters.hpp):
// whether the outputs hold everything the pipeline produced, and the results for the last line.
// Without DDS or processes, so every case is a unit test.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace heslam::supervisor {

struct ProgramReport {
  std::string name;
  std::map<std::string, std::uint64_t> counters;  // its final counters (or the latest seen)
  std::string result;                             // its one-line result, e.g. "tracked N/M frames, ..."
};

struct RunVerdict {
  // Why the run cannot be trusted: a program saw two live writers claim one role (a forged
  // participant, runtime/role_binding.hpp), or the outputs are incomplete (a frame the frontend
  // produced odometry for is missing from the recorder's outputs); else nothing.
  std::optional<std::string> failure;
  // Whether `failure` is a writer conflict: the run's results cannot be trusted at all, so the last
  // line names it before anything else that went wrong (a forger may also stall a reader's end).
  bool writer_conflict = false;
  // The programs' results joined by "; ", the recorder's "tracked N/M" restated against what the
  // source published when the recorder had a smaller count (it missed the source's last status).
  std::string results;
};

RunVerdict judge_run(const std::vector<ProgramReport>& reports);

}  // namespace heslam::supervisor
