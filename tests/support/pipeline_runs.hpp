// Helpers of the multi-process tests that run a shipped pipeline under heslam-supervisor: start it
// on its own domain, wait for it (bounded), find its children, and score its trajectory against the
// EuRoC-layout ground truth. Tests using it link heslam_eval.
#pragma once

#include <signal.h>
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "test_support.hpp"
#include "tools/eval/ape.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::test {

// Bounds of a hung pipeline, not performance assertions.
inline constexpr std::chrono::seconds kPipelineTimeout{300};
inline constexpr std::chrono::seconds kStopTimeout{20};

// heslam-supervisor config/pipelines/PIPELINE.yaml on `domain` with dataset=DATASET,
// output=DIR/LABEL.txt, logs in DIR/logs_LABEL; `pipeline_args` are more NAME=VALUE pipeline
// arguments (e.g. "loop_closer=heslam-loop-closer").
inline std::unique_ptr<ChildProcess> start_pipeline(const std::string& pipeline, const std::filesystem::path& dataset,
                                                    const std::filesystem::path& dir, const std::string& label,
                                                    int domain, const std::vector<std::string>& pipeline_args = {}) {
  std::vector<std::string> args{(source_dir() / "config/pipelines" / (pipeline + ".yaml")).string(),
                                "--domain",
                                std::to_string(domain),
                                "--log-dir",
                                (dir / ("logs_" + label)).string(),
                                "--arg",
                                "dataset=" + dataset.string(),
                                "--arg",
                                "output=" + (dir / (label + ".txt")).string()};
  for (const std::string& arg : pipeline_args) args.insert(args.end(), {"--arg", arg});
  return std::make_unique<ChildProcess>(bin_dir() / "heslam-supervisor", args, dir, "supervisor_" + label);
}

// The supervisor's exit code; a run still going after `timeout` is stopped (SIGTERM) and gives -1
// unless it then exits.
inline int finish(ChildProcess& supervisor, std::chrono::seconds timeout = kPipelineTimeout) {
  std::optional<int> code = supervisor.wait(timeout);
  if (!code) {
    supervisor.signal(SIGTERM);
    code = supervisor.wait(kStopTimeout);
  }
  return code.value_or(-1);
}

inline eval::Trajectory camera_ground_truth(const std::filesystem::path& dataset) {
  eval::ReadOptions options;
  options.extrinsic_path = dataset / "mav0/cam0/sensor.yaml";
  return eval::read_trajectory(dataset / "mav0/state_groundtruth_estimate0/data.csv", options);
}

// The ground truth in the frame of `estimate`: the body poses as they are for a body-frame estimate
// (its '# heslam frame: body' header, the recorder's default), else the cam0 poses.
inline eval::Trajectory ground_truth_for(const std::filesystem::path& dataset, const eval::Trajectory& estimate) {
  if (estimate.frame == eval::PoseFrame::body) {
    return eval::read_trajectory(dataset / "mav0/state_groundtruth_estimate0/data.csv");
  }
  return camera_ground_truth(dataset);
}

inline double ate_rmse_m(const std::filesystem::path& dataset, const std::filesystem::path& trajectory) {
  const eval::Trajectory estimate = eval::read_trajectory(trajectory);
  return eval::compute_ape(ground_truth_for(dataset, estimate), estimate).translation_m.rmse;
}

// The pid of the supervisor's child whose /proc comm is `comm` (the first 15 characters of the
// executable name), 0 if there is none (yet).
inline pid_t child_pid(pid_t supervisor, const std::string& comm) {
  for (const std::filesystem::directory_entry& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
    const std::size_t open = text.find('('), close = text.rfind(')');
    if (open == std::string::npos || close == std::string::npos) continue;
    std::istringstream rest(text.substr(close + 2));
    char state = 0;
    pid_t parent = 0;
    rest >> state >> parent;
    if (parent == supervisor && text.substr(open + 1, close - open - 1) == comm) return std::stoi(name);
  }
  return 0;
}

}  // namespace heslam::test
