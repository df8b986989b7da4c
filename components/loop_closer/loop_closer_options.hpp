// Options of a loop closer process (every implementation): what the core LoopClosing uses, lockstep
// waits, global bundle adjustment and the state file. Detector options are read by the
// implementation (e.g. the BoW closer's vocabulary).
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "components/core/loop/loop_closing.hpp"
#include "runtime/config.hpp"

namespace heslam::loop_closer {

struct LoopCloserProcessOptions {
  // --agents N (docs/agents.md): keyframes come from the frontends of agents 0..N-1 (as the local mapper's).
  int agents = 1;
  LoopClosingOptions closing;  // verification.*; pose_graph.four_dof / pose_graph.gravity_w (correction.pose_graph)
  // pose_graph.gravity_from_odometry: once the odometry carries a gravity (gravity_valid: an inertial run
  // whose IMU is initialized), loop corrections use the 4-DoF pose graph about that gravity (the one of
  // the loop keyframe's frame), whatever pose_graph.four_dof says. Stereo-only runs never carry one.
  bool gravity_from_odometry = true;
  // global_ba.enabled: after a loop correction, bundle-adjust the whole map and publish the result as
  // a second correction (ORB-SLAM2 does, in a thread). Lockstep waits for it, so runs stay
  // deterministic.
  bool global_bundle_adjustment = true;
  // real_time / --real-time: the global BA runs on its own thread while keyframes go on being
  // processed (and a newer loop aborts it), instead of finishing before the keyframe is acknowledged.
  // The real-time pipelines set it; lockstep runs must not.
  bool real_time = false;
  // lockstep.mapper_timeout_s: how long to wait for the local mapper to apply a correction before
  // going on without its acknowledgement (warned, counted), so a dead mapper cannot hang the run.
  std::chrono::milliseconds mapper_timeout{30000};
  // state_file / --state-file FILE: the keyframes already processed and the loops closed, so a
  // restarted loop closer (kill -9) neither repeats nor loses work. Empty: nothing persisted.
  std::filesystem::path state_file;
  // vocabulary.file / --vocabulary FILE (bag-of-words closers): empty = the built default
  // vocabulary (docs/place_recognition.md).
  std::filesystem::path vocabulary;

  // Throws std::runtime_error (one line: file, field, expectation) on a bad field or argument.
  static LoopCloserProcessOptions from_config(const runtime::Config& config, const std::vector<std::string>& rest);
};

}  // namespace heslam::loop_closer
