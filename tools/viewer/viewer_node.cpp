// heslam-viewer's component (see viewer_node.hpp).
#include "tools/viewer/viewer_node.hpp"

#include <chrono>
#include <cstdlib>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>

#include <opencv2/highgui.hpp>

#include "components/messages/checks.hpp"
#include "components/occupancy/occupancy_messages.hpp"
#include "tools/viewer/frame_view_renderer.hpp"
#include "tools/viewer/ground_truth_overlay.hpp"
#include "tools/viewer/map_window.hpp"
#include "tools/viewer/snapshot_writer.hpp"
#include "tools/viewer/top_view_renderer.hpp"
#include "tools/viewer/video_sink.hpp"

namespace heslam::viewer {
namespace {

using Clock = std::chrono::steady_clock;

// The DDS thread re-checks for shutdown at least this often (the waitset also wakes on signals).
constexpr std::chrono::milliseconds kWaitPeriod{200};
// Odometry is small: a deeper best-effort queue keeps the trajectory whole through short stalls of
// the viewer without ever slowing the frontend.
constexpr int kOdometryDepth = 100;
// Without any frontend (odometry writer) for this long, frames are read anyway (a replay watched
// without a frontend, a camera driver alone).
constexpr std::chrono::milliseconds kNoFrontendWait{2000};
// Corrections are rare; the reader keeps the newest (the loop closer writes KEEP_ALL).
constexpr int kCorrectionDepth = 100;
// The 3D map widgets are rebuilt at most this often (VTK actors cost milliseconds each rebuild).
constexpr std::chrono::milliseconds kMapRebuildPeriod{500};
const char* const kFrameWindow = "heslam frame";
const char* const kTopWindow = "heslam map (top view)";

std::string snapshot_label(int index) {
  char label[16];
  std::snprintf(label, sizeof(label), "%04d", index);
  return label;
}

}  // namespace

ViewerNode::ViewerNode(const runtime::CommonArgs& args) : Component("viewer", args) {}

ViewerNode::~ViewerNode() { stop_drawing(); }

void ViewerNode::configure(const runtime::Config& /*config*/) {
  options_ = ViewerOptions::parse(args().rest);
  const char* display = std::getenv("DISPLAY");
  headless_ = options_.headless || display == nullptr || *display == '\0';
  if (headless_ && !options_.headless) {
    if (options_.out_dir.empty()) {
      throw std::runtime_error("no $DISPLAY and no --out DIR: nothing to show and nowhere to write snapshots");
    }
    log().info("no $DISPLAY: headless, snapshots to ", options_.out_dir.string());
  }
  ViewerModelOptions model;
  model.recent_keyframes = options_.recent_keyframes;
  model.covisibility_min_weight = options_.covisibility_min_weight;
  model_ = std::make_unique<ViewerModel>(model);

  // Frames are read from the first odometry on (maybe_subscribe_frames).
  odometry_reader_.emplace(participant(), topics().odometry(),
                           runtime::Qos(runtime::QosRole::kSpy).keep_last(kOdometryDepth));
  // Calibration and map: their own transient-local QoS, so a late viewer gets them from DDS.
  calibration_reader_.emplace(participant(), topics().calibration());
  keyframe_reader_.emplace(participant(), topics().keyframes());
  keyframe_state_reader_.emplace(participant(), topics().keyframe_states());
  point_state_reader_.emplace(participant(), topics().map_points());
  correction_reader_.emplace(participant(), topics().loop_corrections(),
                             runtime::Qos(runtime::QosRole::kCorrections).keep_last(kCorrectionDepth));
  occupancy_reader_.emplace(participant(), topics().occupancy_grid());
  // Frames on a shared-memory domain of their own (--image-transport shm) need a waitset across domains.
  waitset_ = std::make_unique<runtime::WaitSet>(participant(), image_participant().separate_domain()
                                                                   ? runtime::WaitScope::kAllDomains
                                                                   : runtime::WaitScope::kParticipant);
  waitset_->attach(*odometry_reader_);
  waitset_->attach(*calibration_reader_);
  waitset_->attach(*keyframe_reader_);
  waitset_->attach(*keyframe_state_reader_);
  waitset_->attach(*point_state_reader_);
  waitset_->attach(*correction_reader_);
  waitset_->attach(*occupancy_reader_);
  run_end_.emplace(participant(), topics());
  waitset_->attach(run_end_->reader());
  std::ostringstream drawing;
  if (!headless_ || !options_.record_file.empty()) {
    drawing << ", drawing at " << options_.draw_rate_hz << " Hz";
  } else {
    drawing << ", drawing only for snapshots";
  }
  log().info(headless_ ? "headless" : "display", drawing.str(),
             options_.out_dir.empty() ? std::string() : ", snapshots to " + options_.out_dir.string(),
             options_.record_file.empty() ? std::string() : ", recording to " + options_.record_file.string());
}

void ViewerNode::run() {
  started_ = Clock::now();
  draw_thread_ = std::thread([this] { draw_loop(); });
  while (!shutdown_requested()) {
    if (waitset_->wait(kWaitPeriod) == runtime::Wake::kShutdown) break;
    take_all();
    maybe_subscribe_frames();
    // A viewer started by hand ends with the run it watches (one started by the supervisor is
    // stopped by it anyway): the final pictures then show the finished map.
    if (const std::optional<std::string> ended = run_end_->poll()) {
      log().info(*ended, "; writing the final pictures");
      break;
    }
  }
  take_all();  // what arrived last, for the final pictures
  stop_drawing();
  if (draw_error_) std::rethrow_exception(draw_error_);
  std::lock_guard<std::mutex> lock(model_mutex_);
  if (!model_->received_anything()) {
    // Empty pictures are no result: say why, exit non-zero.
    throw std::runtime_error("received no frame, odometry or map sample under '" + topics().ns() + "/' on domain " +
                             std::to_string(args().domain_id) +
                             " (is a pipeline running with the same --domain / --namespace?)");
  }
}

void ViewerNode::stop_drawing() {
  {
    std::lock_guard<std::mutex> lock(stop_mutex_);
    stop_ = true;
  }
  stop_signal_.notify_all();
  if (draw_thread_.joinable()) draw_thread_.join();
}

// A lockstep replay starts publishing once ANY reader of camera/stereo matched, and then waits for the
// frontend's acknowledgement of frame 0. A viewer whose reader matched before the frontend's would let
// frame 0 go out before the frontend hears it (a stalled start until the replay's ack timeout). So the
// viewer reads frames only after the frontend published its first odometry (frame 0 is then done), or
// when no frontend appeared within kNoFrontendWait. Joining mid-run is safe: the replay sends the
// current frame again to a new reader and the frontend acknowledges it without tracking it twice.
void ViewerNode::maybe_subscribe_frames() {
  if (frame_reader_) return;
  const bool no_frontend = odometry_reader_->matched_writers() == 0 && Clock::now() - started_ >= kNoFrontendWait;
  if (!odometry_seen_ && !no_frontend) return;
  // Best effort, keep the newest only: a slow viewer drops frames, never the camera's.
  frame_reader_.emplace(image_participant().get(), topics().stereo(), runtime::Qos(runtime::QosRole::kSpy));
  waitset_->attach(*frame_reader_);
  log().debug("reading ", topics().stereo().name, odometry_seen_ ? " (the frontend is running)" : " (no frontend)");
}

std::size_t ViewerNode::take_all() {
  std::size_t taken = 0;
  const auto now = Clock::now();
  // One helper per topic: apply under the model lock, count and report a bad sample, go on.
  auto apply = [&](auto& reader, const char* counter, auto&& handle) {
    auto samples = reader.take();
    if (samples.empty()) return;
    taken += samples.size();
    std::lock_guard<std::mutex> lock(model_mutex_);
    for (auto& received : samples) {
      try {
        // The shared checks (finite numbers, sizes, ids): a NaN pose is never drawn.
        if (received.info.valid_data) {
          if (auto problem = messages::check(*received.sample)) throw std::runtime_error(*problem);
        }
        if (handle(received)) stats().count(counter);
      } catch (const std::exception& error) {
        const std::string bad = std::string("bad_") + counter;
        stats().count(bad);
        log().warn_throttled(bad, "topic '", reader.name(), "': ", error.what(), "; skipped (counted as ", bad, ")");
      }
    }
  };
  apply(*calibration_reader_, "calibrations", [&](auto& r) {
    if (r.info.valid_data) model_->set_calibration(*r.sample);
    return r.info.valid_data;
  });
  apply(*keyframe_reader_, "keyframes", [&](auto& r) {
    if (r.info.valid_data) model_->add_keyframe(*r.sample);
    return r.info.valid_data;
  });
  apply(*keyframe_state_reader_, "keyframe_states", [&](auto& r) {
    if (r.info.valid_data) model_->apply_keyframe_state(*r.sample);
    return r.info.valid_data;
  });
  apply(*point_state_reader_, "point_states", [&](auto& r) {
    if (r.info.valid_data) {
      model_->apply_point_state(*r.sample);
    } else if (r.info.disposed) {
      model_->point_disposed(r.sample->id);
    }
    return true;
  });
  apply(*correction_reader_, "loop_corrections", [&](auto& r) {
    if (r.info.valid_data) model_->apply_correction(*r.sample, now);
    return r.info.valid_data;
  });
  // heslam-occupancy's grid (idl/occupancy.idl has its own check: sizes and cell values).
  for (auto& received : occupancy_reader_->take()) {
    ++taken;
    if (!received.info.valid_data) continue;
    try {
      occupancy::ReceivedGrid grid = occupancy::from_message(*received.sample);
      std::lock_guard<std::mutex> lock(model_mutex_);
      model_->set_occupancy(std::move(grid.grid), grid.T_wg);
      stats().count("occupancy_grids");
    } catch (const std::exception& error) {
      stats().count("bad_occupancy_grids");
      log().warn_throttled("bad_occupancy_grids", "topic '", occupancy_reader_->name(), "': ", error.what(),
                           "; skipped (counted as bad_occupancy_grids)");
    }
  }
  if (frame_reader_) {
    apply(*frame_reader_, "frames", [&](auto& r) {
      if (r.info.valid_data) model_->add_frame(*r.sample);
      return r.info.valid_data;
    });
  }
  apply(*odometry_reader_, "odometry", [&](auto& r) {
    if (r.info.valid_data) model_->add_odometry(*r.sample, now);
    odometry_seen_ = odometry_seen_ || r.info.valid_data;
    return r.info.valid_data;
  });
  return taken;
}

void ViewerNode::draw_loop() {
  try {
    const auto period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / options_.draw_rate_hz));
    const auto snapshot_period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options_.snapshot_every_s));
    Layers layers;
    const TopViewRenderer top_view(kDefaultTopViewSize, options_.fit);
    HistogramEqualizerOptions equalizer;
    equalizer.mode = options_.he_mode;
    FrameViewRenderer frame_view(equalizer);
    std::optional<GroundTruthOverlay> ground_truth;
    if (!options_.gt_file.empty()) ground_truth.emplace(options_.gt_file, options_.gt_extrinsic);
    std::optional<SnapshotWriter> snapshots;
    if (!options_.out_dir.empty()) snapshots.emplace(options_.out_dir);
    std::optional<VideoSink> video;
    if (!options_.record_file.empty()) video.emplace(options_.record_file, options_.draw_rate_hz);

    bool windows = !headless_;
    std::unique_ptr<MapWindow> map_window;
    if (windows) {
      try {
        map_window = MapWindow::create();
        cv::namedWindow(kFrameWindow, cv::WINDOW_AUTOSIZE);
        if (!map_window) cv::namedWindow(kTopWindow, cv::WINDOW_AUTOSIZE);
      } catch (const std::exception& error) {
        if (!snapshots) throw std::runtime_error(std::string("cannot open a window: ") + error.what());
        log().warn("cannot open a window (", error.what(), "); headless, snapshots to ", options_.out_dir.string());
        map_window.reset();
        windows = false;
      }
    }

    std::vector<Eigen::Vector3d> aligned_ground_truth;
    std::tuple<std::uint64_t, std::size_t, std::size_t, std::size_t> last_map{~0ULL, 0, 0, 0};
    Clock::time_point last_rebuild{};
    Clock::time_point next_snapshot = Clock::now() + snapshot_period;
    int snapshot_index = 0;
    auto make_scene = [&](Clock::time_point now) {
      std::lock_guard<std::mutex> lock(model_mutex_);
      return model_->scene(now);
    };

    for (;;) {
      {
        std::unique_lock<std::mutex> lock(stop_mutex_);
        if (stop_signal_.wait_for(lock, period, [&] { return stop_; })) break;
      }
      const Clock::time_point now = Clock::now();
      bool want_snapshot = snapshots && options_.snapshot_every_s > 0.0 && now >= next_snapshot;
      if (!windows && !video && !want_snapshot) continue;  // headless: draw only what is written
      const auto timer = stats().time("draw");
      Scene scene = make_scene(now);
      const auto map_key =
          std::make_tuple(scene.map_version, scene.map_keyframes, scene.points.size(), scene.loop_corrections);
      const bool map_changed = map_key != last_map && now - last_rebuild >= kMapRebuildPeriod;
      if (map_changed) {
        last_map = map_key;
        last_rebuild = now;
        if (ground_truth) aligned_ground_truth = ground_truth->aligned(scene.trajectory_w, scene.trajectory_stamps_ns);
      }
      scene.ground_truth_w = aligned_ground_truth;
      const cv::Mat frame_image = frame_view.render(scene);
      if (video) video->write(frame_image);
      cv::Mat top_image;
      cv::Mat view_3d;
      if (windows) {
        std::vector<int> keys;
        if (map_window) {
          map_window->update(scene, layers, map_changed, 1, keys);
          if (map_window->closed()) runtime::request_shutdown();
        } else {
          top_image = top_view.render(scene, layers).image;
          cv::imshow(kTopWindow, top_image);
        }
        cv::imshow(kFrameWindow, frame_image);
        if (const int key = cv::waitKey(1); key >= 0) keys.push_back(key & 0xff);
        for (const int key : keys) {
          if (key == 'q' || key == 27) {
            log().info("closed by the user (the pipeline goes on)");
            runtime::request_shutdown();
          } else if (key == 's' && snapshots) {
            want_snapshot = true;
          } else if (layers.toggle(key)) {
            last_map = {~0ULL, 0, 0, 0};  // redraw the 3D layers
            last_rebuild = {};
          }
        }
      }
      if (want_snapshot) {
        if (top_image.empty()) top_image = top_view.render(scene, layers).image;
        if (map_window) view_3d = map_window->screenshot();
        snapshots->write(snapshot_label(++snapshot_index), top_image, frame_image, view_3d);
        stats().count("snapshots");
        if (options_.snapshot_every_s > 0.0) {
          while (next_snapshot <= now) next_snapshot += snapshot_period;
        }
      }
    }

    // The final pictures and counts.
    Scene scene = make_scene(Clock::now());
    if (ground_truth) scene.ground_truth_w = ground_truth->aligned(scene.trajectory_w, scene.trajectory_stamps_ns);
    const TopView top = top_view.render(scene, layers);
    const cv::Mat frame_image = frame_view.render(scene);
    cv::Mat view_3d;
    if (map_window) {
      std::vector<int> ignored;
      map_window->update(scene, layers, true, 1, ignored);
      view_3d = map_window->screenshot();
    }
    FrameCounts counts;
    {
      std::lock_guard<std::mutex> lock(model_mutex_);
      counts = model_->frame_counts();
    }
    std::map<std::string, std::string> stats_file{
        {"frames_received", std::to_string(counts.received)},
        {"frames_drawn", std::to_string(counts.drawn)},
        {"frames_not_drawn", std::to_string(counts.not_drawn())},
        {"frames_missed", std::to_string(counts.missed)},
        {"frame_seq", scene.has_frame ? std::to_string(scene.frame_seq) : "none"},
        {"frame_stamp_ns", scene.has_frame ? std::to_string(scene.frame_stamp_ns) : "none"},
        {"map_keyframes", std::to_string(scene.map_keyframes)},
        {"frustums_drawn", std::to_string(top.frustums_drawn)},
        {"map_points", std::to_string(scene.map_points)},
        {"points_drawn", std::to_string(top.points_drawn)},
        {"covisibility_edges", std::to_string(scene.covisibility.size())},
        {"spanning_tree_edges", std::to_string(scene.spanning_tree.size())},
        {"loop_corrections", std::to_string(scene.loop_corrections)},
        {"trajectory_points", std::to_string(scene.trajectory_w.size())},
        {"ground_truth_points", std::to_string(scene.ground_truth_w.size())},
        {"display", headless_ ? "headless" : (map_window ? "viz" : "highgui")},
    };
    if (snapshots) {
      snapshots->write("final", top.image, frame_image, view_3d);
      snapshots->write_stats(stats_file);
    }
    if (video) log().info(video->close());
    log().info("drew ", counts.drawn, " of ", counts.received, " frames received (", counts.not_drawn(),
               " dropped before drawing, ", counts.missed, " never received); map ", scene.map_keyframes,
               " keyframes (", top.frustums_drawn, " frustums drawn), ", scene.map_points, " points, ",
               scene.loop_corrections, " loop corrections",
               snapshots ? "; pictures in " + snapshots->dir().string() : std::string());
    if (windows) cv::destroyAllWindows();
  } catch (...) {
    draw_error_ = std::current_exception();
    runtime::request_shutdown();
  }
}

}  // namespace heslam::viewer
