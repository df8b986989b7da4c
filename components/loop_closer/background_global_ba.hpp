// The global bundle adjustment after a loop, on its own thread (ORB-SLAM2's RunGlobalBundleAdjustment
// thread): it works on a copy of the map taken when it starts, so a real-time loop closer keeps taking
// and processing keyframes meanwhile; a newer loop, or shutdown, aborts it (the solver checks the flag
// after every iteration). Lockstep runs start it and collect it at once, so they stay deterministic.
//
// Its result is a correction computed on the copy's map version; the local mapper moves keyframes
// created since then with their spanning-tree parent (ARCHITECTURE.md), as for any correction.
#pragma once

#include <atomic>
#include <chrono>
#include <optional>
#include <thread>

#include "components/core/loop/loop_closing.hpp"

namespace heslam::loop_closer {

class BackgroundGlobalBa {
 public:
  BackgroundGlobalBa() = default;
  BackgroundGlobalBa(const BackgroundGlobalBa&) = delete;
  BackgroundGlobalBa& operator=(const BackgroundGlobalBa&) = delete;
  ~BackgroundGlobalBa() { abort(); }

  // Starts adjusting `map` (the caller's copy) for the loop closed at `loop_kf`. `closing` must
  // outlive the run; only its camera is read, so the caller may go on processing keyframes with it.
  // A run still going is aborted first.
  // `inertial`: the IMU factors of an inertial run (global_inertial_chain.hpp), nullopt: visual only.
  void start(const LoopClosing& closing, Map map, KeyframeId loop_kf,
             std::optional<GlobalInertialInput> inertial = std::nullopt);
  // True from start() until the result was collected or the run aborted.
  bool running() const { return thread_.joinable(); }
  // True when a run has finished and waits to be collected.
  bool finished() const { return thread_.joinable() && done_.load(); }
  // Stops a running adjustment (if any) and drops its result; returns whether one was running.
  bool abort();

  struct Outcome {
    std::optional<LoopCorrection> correction;  // loop_kf set; nullopt when aborted
    double elapsed_ms = 0.0;
    double cpu_ms = 0.0;                // the thread's CPU time (what the load does not inflate)
    GlobalBundleAdjustmentStats stats;  // the solver's figures (imu_factors: 0 visual only)
  };
  // Waits for the run started last and returns its result.
  Outcome collect();

 private:
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> done_{false};
  std::optional<LoopCorrection> result_;  // written by the thread before done_, read after join
  GlobalBundleAdjustmentStats stats_;     // likewise
  double cpu_ms_ = 0.0;                   // likewise
  std::chrono::steady_clock::time_point started_;
};

}  // namespace heslam::loop_closer
