// judge_run: the counters of the source, the frontend and the recorder held against each other.
#include "runtime/supervisor/run_verdict.hpp"

#include <algorithm>

#include "runtime/run_counters.hpp"

namespace heslam::supervisor {
namespace {

// The largest value of `counter` among the reports, nothing when none has it.
std::optional<std::uint64_t> largest(const std::vector<ProgramReport>& reports, const char* counter) {
  std::optional<std::uint64_t> value;
  for (const ProgramReport& report : reports) {
    const auto it = report.counters.find(counter);
    if (it != report.counters.end()) value = std::max(value.value_or(0), it->second);
  }
  return value;
}

std::optional<std::uint64_t> counter_of(const ProgramReport& report, const char* counter) {
  const auto it = report.counters.find(counter);
  return it == report.counters.end() ? std::nullopt : std::optional(it->second);
}

// "tracked N/M frames, K lost, REST" with M = published, K = published - N; other text unchanged.
std::string restate_tracked(const std::string& result, std::uint64_t with_pose, std::uint64_t published) {
  constexpr std::string_view kTracked = "tracked ";
  constexpr std::string_view kLost = " lost";
  const std::size_t lost = result.find(kLost);
  if (!result.starts_with(kTracked) || lost == std::string::npos) return result;
  return std::string(kTracked) + std::to_string(with_pose) + "/" + std::to_string(published) + " frames, " +
         std::to_string(published - std::min(published, with_pose)) + std::string(kLost) +
         result.substr(lost + kLost.size());
}

// "NAME: two live writers claimed one role on TOPIC[, TOPIC] (N times)..." for the first program that
// counted writer conflicts (runtime/run_counters.hpp), nothing when none did.
std::optional<std::string> writer_conflicts(const std::vector<ProgramReport>& reports) {
  for (const ProgramReport& report : reports) {
    const std::optional<std::uint64_t> conflicts = counter_of(report, runtime::kWriterConflicts);
    if (!conflicts || *conflicts == 0) continue;
    std::string topics;
    for (const auto& [name, value] : report.counters) {
      if (value == 0 || !name.starts_with(runtime::kWriterConflictsOn)) continue;
      topics += (topics.empty() ? "" : ", ") + name.substr(std::string_view(runtime::kWriterConflictsOn).size());
    }
    return report.name + ": two live writers claimed one role" + (topics.empty() ? "" : " on " + topics) + " (" +
           std::to_string(*conflicts) + (*conflicts == 1 ? " conflict" : " conflicts") +
           ": a forged participant or a second copy of a component; its log names both writers)";
  }
  return std::nullopt;
}

// "NAME was stopped before the end of its input..." for the first source that counted frames it did
// not play (runtime/run_counters.hpp), nothing when none did.
std::optional<std::string> input_cut_short(const std::vector<ProgramReport>& reports) {
  for (const ProgramReport& report : reports) {
    const std::optional<std::uint64_t> not_played = counter_of(report, runtime::kFramesNotPlayed);
    if (!not_played || *not_played == 0) continue;
    const std::optional<std::uint64_t> total = counter_of(report, runtime::kFramesTotal);
    return report.name + " was stopped before the end of its input (" + std::to_string(*not_played) +
           (total ? " of its " + std::to_string(*total) : std::string()) +
           " frames not played): the outputs hold only the run's beginning";
  }
  return std::nullopt;
}

// Several agents (docs/agents.md): recorder_X records the frames of frontend_X, played by replay_X, so
// its counts are held against theirs; `counter` of the program `role`_X, nothing when there is none.
std::optional<std::uint64_t> of_same_agent(const std::vector<ProgramReport>& reports, const std::string& recorder,
                                           const std::string& role, const char* counter) {
  const std::string prefix = "recorder_";
  if (!recorder.starts_with(prefix)) return std::nullopt;
  const std::string name = role + "_" + recorder.substr(prefix.size());
  for (const ProgramReport& report : reports) {
    if (report.name == name) return counter_of(report, counter);
  }
  return std::nullopt;
}

}  // namespace

RunVerdict judge_run(const std::vector<ProgramReport>& reports) {
  RunVerdict verdict;
  verdict.failure = writer_conflicts(reports);
  verdict.writer_conflict = verdict.failure.has_value();
  if (!verdict.failure) verdict.failure = input_cut_short(reports);
  const std::optional<std::uint64_t> all_published = largest(reports, runtime::kFramesPublished);
  const std::optional<std::uint64_t> all_produced = largest(reports, runtime::kOdometryFrames);
  for (const ProgramReport& report : reports) {
    std::string result = report.result;
    const std::optional<std::uint64_t> own_published =
        of_same_agent(reports, report.name, "replay", runtime::kFramesPublished);
    const std::optional<std::uint64_t> own_produced =
        of_same_agent(reports, report.name, "frontend", runtime::kOdometryFrames);
    const std::optional<std::uint64_t> published = own_published ? own_published : all_published;
    const std::optional<std::uint64_t> produced = own_produced ? own_produced : all_produced;
    const std::optional<std::uint64_t> recorded = counter_of(report, runtime::kFramesRecorded);
    if (recorded && produced && *recorded < *produced && !verdict.failure) {
      verdict.failure = report.name + ": " + std::to_string(*produced - *recorded) + " of the " +
                        std::to_string(*produced) + " frames the frontend produced odometry for are missing from " +
                        "its output (it recorded " + std::to_string(*recorded) +
                        "; it was stalled or cut off while they were published)";
    }
    const std::optional<std::uint64_t> accounted = counter_of(report, runtime::kFramesAccounted);
    const std::optional<std::uint64_t> with_pose = counter_of(report, runtime::kFramesWithPose);
    if (accounted && with_pose && published && *accounted < *published) {
      result = restate_tracked(result, *with_pose, *published);
    }
    if (!result.empty()) verdict.results += (verdict.results.empty() ? "" : "; ") + result;
  }
  return verdict;
}

}  // namespace heslam::supervisor
