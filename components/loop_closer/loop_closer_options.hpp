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
  // global_ba.imu: in inertial runs (once the pose graph is 4-DoF about a gravity: the odometry's or
  // pose_graph.four_dof's) the global BA also holds a velocity and biases per keyframe and IMU factors
  // between consecutive keyframes (docs/loop_closer.md, Global BA with IMU factors). The loop closer then
  // subscribes imu/readings, imu/calibration and calibration. Stereo-only runs are unchanged either way.
  bool global_ba_imu = false;
  // global_ba.imu_buffer_s: IMU readings kept (older ones dropped): keyframes further back get no IMU
  // factor. 600 s at 200 Hz is ~7 MB.
  double imu_buffer_s = 600.0;
  // global_ba.imu_wait_s: lockstep only: before a global BA, wait at most this long for the IMU to cover
  // the newest keyframe (then it goes on with what it has, warned, counted).
  double imu_wait_s = 2.0;
  // global_ba.imu_max_interval_s: two consecutive keyframes further apart get no IMU factor.
  double imu_max_interval_s = 3.0;
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
  // --mapper-map-file FILE (the session pipelines: multi-session mapping): the local mapper's map file.
  // When this run's mapper wrote it before the loop closer started (it loaded a saved map), the
  // keyframes (with the features the state topics do not carry) and points are taken from it, so the
  // saved map's places are loop and merge candidates from the first keyframe on. Empty: none.
  std::filesystem::path mapper_map_file;
  // vocabulary.file / --vocabulary FILE (bag-of-words closers): empty = the built default
  // vocabulary (docs/place_recognition.md).
  std::filesystem::path vocabulary;

  // Throws std::runtime_error (one line: file, field, expectation) on a bad field or argument.
  static LoopCloserProcessOptions from_config(const runtime::Config& config, const std::vector<std::string>& rest);
};

}  // namespace heslam::loop_closer
