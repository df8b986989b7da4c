// heslam-viewer's component: DDS readers on the main thread feed the ViewerModel; a drawing thread
// renders the 3D / top view and the 2D view at its own rate, writes snapshots and recordings.
//
// It must never slow the pipeline: frames and odometry are read best effort, keep-last (a reader
// that falls behind loses samples, it never makes a writer wait), the map topics with their own
// transient-local QoS (so a viewer started late gets the whole map), and no pipeline process waits
// for the viewer. Frames replaced before they were drawn are counted.
#pragma once

#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "runtime/component.hpp"
#include "runtime/run_end_watch.hpp"
#include "tools/viewer/viewer_model.hpp"
#include "tools/viewer/viewer_options.hpp"

namespace heslam::viewer {

class ViewerNode final : public runtime::Component {
 public:
  explicit ViewerNode(const runtime::CommonArgs& args);
  ~ViewerNode() override;

 private:
  void configure(const runtime::Config& config) override;
  void run() override;
  bool accepts_positional_args() const override { return true; }  // the viewer's own flags (ViewerOptions)

  // Takes every waiting sample and applies it to the model; returns the number taken.
  std::size_t take_all();
  // Creates the camera/stereo reader once it cannot disturb a lockstep start (see the .cpp).
  void maybe_subscribe_frames();
  void draw_loop();
  void stop_drawing();

  ViewerOptions options_;
  bool headless_ = false;
  std::mutex model_mutex_;
  std::unique_ptr<ViewerModel> model_;
  std::unique_ptr<runtime::WaitSet> waitset_;
  std::optional<runtime::Reader<msg::StereoFrame>> frame_reader_;
  std::optional<runtime::Reader<msg::Odometry>> odometry_reader_;
  std::optional<runtime::Reader<msg::StereoCalibration>> calibration_reader_;
  std::optional<runtime::Reader<msg::Keyframe>> keyframe_reader_;
  std::optional<runtime::Reader<msg::KeyframeState>> keyframe_state_reader_;
  std::optional<runtime::Reader<msg::MapPointState>> point_state_reader_;
  std::optional<runtime::Reader<msg::LoopCorrection>> correction_reader_;
  std::optional<runtime::Reader<msg::OccupancyGrid2D>> occupancy_reader_;
  std::optional<runtime::RunEndWatch> run_end_;

  std::mutex stop_mutex_;
  std::condition_variable stop_signal_;
  bool stop_ = false;
  std::thread draw_thread_;
  std::exception_ptr draw_error_;
  bool odometry_seen_ = false;
  std::chrono::steady_clock::time_point started_{};
};

}  // namespace heslam::viewer
