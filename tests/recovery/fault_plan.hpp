// A seeded plan of kill -9 faults for one lockstep run of a full-system pipeline: at which frame
// (the run's progress, not wall time, so a seed replays the same faults on a faster or slower
// machine) which components die, and how far apart. Single kills, near-simultaneous pairs (a power
// glitch, an OOM kill) and every component but the supervisor.
#pragma once

#include <algorithm>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace heslam::test {

// The full system's components under heslam-supervisor (config/pipelines/euroc.yaml).
inline const std::vector<std::string>& pipeline_components() {
  static const std::vector<std::string> names{"recorder", "local_mapper", "loop_closer", "frontend", "replay"};
  return names;
}

// /proc/<pid>/comm of a component: the first 15 characters of its executable's name.
inline std::string component_comm(const std::string& component) {
  if (component == "recorder") return "heslam-recorder";
  if (component == "local_mapper") return "heslam-local-ma";
  if (component == "loop_closer") return "heslam-loop-clo";
  if (component == "frontend") return "heslam-frontend";
  if (component == "replay") return "heslam-replay";
  return component;
}

struct KillEvent {
  int at_frame = 0;                     // once the run has done this many frames (processed or recorded)
  std::vector<std::string> components;  // killed in this order ...
  std::vector<int> gaps_ms;             // ... this long after the one before (gaps_ms[0] is 0)

  std::string describe() const {
    std::ostringstream text;
    text << "frame " << at_frame << ":";
    for (std::size_t i = 0; i < components.size(); ++i) {
      text << (i == 0 ? " " : " +" + std::to_string(gaps_ms[i]) + "ms ") << components[i];
    }
    return text.str();
  }
};

struct FaultPlanOptions {
  int kills = 3;         // events per run
  int first_frame = 10;  // not before this frame: the map and every process exist
  int last_frame = 150;  // not after this one: the replay has frames left to send (of 160)
  int max_gap_ms = 500;  // near-simultaneous: the two deaths of a pair at most this far apart
  int all_gap_ms = 100;  // all but the supervisor: one after the other within this
};

// Event kinds by probability: a single component 40 %, two 40 %, all of them 20 %.
inline std::vector<KillEvent> plan_faults(std::uint64_t seed, const FaultPlanOptions& options = {}) {
  std::mt19937_64 random(seed);
  const auto uniform = [&](int low, int high) { return std::uniform_int_distribution<int>(low, high)(random); };
  std::vector<int> frames;
  for (int i = 0; i < options.kills; ++i) frames.push_back(uniform(options.first_frame, options.last_frame));
  std::sort(frames.begin(), frames.end());
  std::vector<KillEvent> plan;
  for (const int frame : frames) {
    KillEvent event;
    event.at_frame = frame;
    std::vector<std::string> names = pipeline_components();
    std::shuffle(names.begin(), names.end(), random);
    const int kind = uniform(0, 9);
    const std::size_t count = kind < 4 ? 1 : kind < 8 ? 2 : names.size();
    const int max_gap_ms = count == names.size() ? options.all_gap_ms : options.max_gap_ms;
    for (std::size_t i = 0; i < count; ++i) {
      event.components.push_back(names[i]);
      event.gaps_ms.push_back(i == 0 ? 0 : uniform(0, max_gap_ms));
    }
    plan.push_back(event);
  }
  return plan;
}

}  // namespace heslam::test
