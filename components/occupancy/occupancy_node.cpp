// heslam-occupancy's component (see occupancy_node.hpp).
#include "components/occupancy/occupancy_node.hpp"

#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>

#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/pose.hpp"
#include "components/occupancy/occupancy_messages.hpp"
#include "runtime/atomic_file.hpp"
#include "runtime/run_id.hpp"

namespace heslam::occupancy {
namespace {

using Clock = std::chrono::steady_clock;

// The DDS thread re-checks for shutdown at least this often (the waitset also wakes on signals).
constexpr std::chrono::milliseconds kWaitPeriod{200};
// Frames are big (a raw pair): the reader keeps a few; the ring in this process keeps frame_ring.
constexpr int kFrameReaderDepth = 8;
const char* const kRunFile = "RUN";
const char* const kCloudExtension = ".cloud";
const char* const kViewExtension = ".view";  // the multi-view refinement's kept views

// This thread's CPU time: the work per keyframe apart from the machine's load (wall times grow with it).
double thread_cpu_ms() {
  timespec now{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

std::filesystem::path cloud_file(const std::filesystem::path& dir, std::uint64_t id) {
  return dir / (std::to_string(id) + kCloudExtension);
}

std::filesystem::path view_file(const std::filesystem::path& dir, std::uint64_t id) {
  return dir / (std::to_string(id) + kViewExtension);
}

}  // namespace

OccupancyNode::OccupancyNode(const runtime::CommonArgs& args) : Component("occupancy", args) {}

OccupancyNode::~OccupancyNode() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void OccupancyNode::configure(const runtime::Config& config) {
  options_ = OccupancyProcessOptions::from_config(config, args().rest);
  map_ = std::make_unique<OccupancyMap>(options_.map);
  equalizer_.emplace(options_.he);
  load_state();
  calibration_reader_.emplace(participant(), topics().calibration());
  // Reliable like the frontend's reader, keep-last: a busy worker never slows the replay, and the DDS
  // thread only copies frames into the ring.
  frame_reader_.emplace(image_participant().get(), topics().stereo(),
                        runtime::Qos(runtime::QosRole::kImages).keep_last(kFrameReaderDepth));
  keyframe_reader_.emplace(participant(), topics().keyframes());
  keyframe_state_reader_.emplace(participant(), topics().keyframe_states());
  if (options_.up_from_gravity) odometry_reader_.emplace(participant(), topics().odometry());
  grid_writer_.emplace(participant(), topics().occupancy_grid());
  if (options_.cloud_max_points > 0) cloud_writer_.emplace(participant(), topics().dense_cloud());
  save_reader_.emplace(participant(), topics().occupancy_save_request());
  save_writer_.emplace(participant(), topics().occupancy_save_reply());
  waitset_ = std::make_unique<runtime::WaitSet>(participant(), image_participant().separate_domain()
                                                                   ? runtime::WaitScope::kAllDomains
                                                                   : runtime::WaitScope::kParticipant);
  waitset_->attach(*calibration_reader_);
  waitset_->attach(*frame_reader_);
  waitset_->attach(*keyframe_reader_);
  waitset_->attach(*keyframe_state_reader_);
  waitset_->attach(*save_reader_);
  if (odometry_reader_) waitset_->attach(*odometry_reader_);
  log().info(
      "voxels ", options_.map.voxels.resolution_m, " m, grid band [", options_.map.band.min_m, ", ",
      options_.map.band.max_m, "] m along ", to_string(options_.map.up),
      options_.up_from_gravity ? " (against gravity once the odometry gives one)" : "", ", depth ",
      options_.stereo.min_depth_m, "-", options_.stereo.max_depth_m, " m, HE ", to_string(options_.he.mode),
      options_.settings_file.empty() ? std::string(" (no settings file)")
                                     : " (" + options_.settings_file.string() + ")",
      options_.output_stem.empty() ? std::string() : ", output " + options_.output_stem.string() + ".pgm/.yaml/.ply",
      map_->clouds() ? ", " + std::to_string(map_->clouds()) + " keyframe clouds from the state folder"
                     : std::string());
}

void OccupancyNode::load_state() {
  if (options_.state_dir.empty()) return;
  namespace fs = std::filesystem;
  fs::create_directories(options_.state_dir);
  const std::string run = runtime::supervisor_run_id();
  std::string stored;
  {
    std::ifstream in(options_.state_dir / kRunFile);
    std::getline(in, stored);
  }
  if (stored != run) {
    // Another run's clouds (or none): start empty.
    for (const auto& entry : fs::directory_iterator(options_.state_dir)) {
      const auto extension = entry.path().extension();
      if (extension == kCloudExtension || extension == kViewExtension) fs::remove(entry.path());
    }
    runtime::replace_file_contents(options_.state_dir / kRunFile, run + "\n");
    return;
  }
  for (const auto& entry : fs::directory_iterator(options_.state_dir)) {
    if (entry.path().extension() == kViewExtension) {
      try {
        KeptView view = read_view(entry.path());
        next_view_sequence_ = std::max(next_view_sequence_, view.sequence + 1);
        loaded_views_.push_back(std::move(view));
      } catch (const std::exception& error) {
        stats().count("bad_state_files");
        log().warn(error.what(), "; removed (counted as bad_state_files)");
        fs::remove(entry.path());
      }
      continue;
    }
    if (entry.path().extension() != kCloudExtension) continue;
    try {
      std::uint64_t id = 0;
      KeyframeCloud cloud = read_cloud(entry.path(), id);
      seen_keyframes_[id] = true;
      map_->add_cloud(id, std::move(cloud));
      stats().count("clouds_loaded");
    } catch (const std::exception& error) {
      stats().count("bad_state_files");
      log().warn(error.what(), "; removed (counted as bad_state_files)");
      fs::remove(entry.path());
    }
  }
}

void OccupancyNode::run() {
  worker_ = std::thread([this] { worker_loop(); });
  while (!shutdown_requested()) {
    if (waitset_->wait(kWaitPeriod) == runtime::Wake::kShutdown) break;
    take_all();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (worker_error_) break;
    }
  }
  take_all();
  // The final map in the newest gravity's frame, whatever the last change the worker saw: it then
  // depends on the last gravity only, not on when the small refinements arrived.
  if (latest_up_w_ && latest_up_w_ != sent_up_w_) send_up(*latest_up_w_);
  // Poses or culls of keyframes this process never received (states may come before their keyframe,
  // so only the end can tell): counted, they moved nothing.
  std::size_t unknown = 0;
  for (const auto& [id, state] : has_state_) unknown += seen_keyframes_.count(id) == 0;
  for (const std::uint64_t id : culled_ids_) unknown += seen_keyframes_.count(id) == 0 && has_state_.count(id) == 0;
  if (unknown > 0) {
    stats().count("states_of_unknown_keyframes", unknown);
    log().warn(unknown, " keyframe state(s) (pose, correction or cull) of keyframes never received on ",
               topics().keyframes().name, ": skipped (counted as states_of_unknown_keyframes)");
  }
  const std::size_t unmatched = pending_.size();
  if (unmatched > 0) {
    bool calibrated = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      calibrated = rectifier_ != nullptr;
    }
    const char* counter = calibrated ? "keyframes_without_frame" : "keyframes_without_calibration";
    stats().count(counter, unmatched);
    log().warn(unmatched, " keyframe(s) still waiting for their ", calibrated ? "frame" : "calibration",
               " at the end: skipped (counted as ", counter, ")");
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
  if (worker_error_) std::rethrow_exception(worker_error_);
  write_outputs();
  log_stages();
}

void OccupancyNode::log_stages() {
  // Per keyframe: disparity (rectify, HE, SGBM, cloud) and fusion, wall and this thread's CPU; the
  // rebuilds; the live outputs (tools/bench/realtime/realtime_pipeline.sh reads these lines).
  for (const runtime::StageSummary& stage : stats().stages()) {
    std::ostringstream line;
    line << std::fixed << std::setprecision(2) << "stage " << std::left << std::setw(20) << stage.name << " median "
         << std::right << std::setw(8) << stage.p50_ms << " ms  p90 " << std::setw(8) << stage.p90_ms << " ms  max "
         << std::setw(8) << stage.max_ms << " ms  (" << stage.count << ")";
    log().info(line.str());
  }
}

void OccupancyNode::take_all() {
  auto apply = [&](auto& reader, const char* counter, auto&& handle) {
    for (auto& received : reader.take()) {
      if (!received.info.valid_data) continue;
      try {
        if (auto problem = messages::check(*received.sample)) throw std::runtime_error(*problem);
        handle(*received.sample);
        stats().count(counter);
      } catch (const std::exception& error) {
        const std::string bad = std::string("bad_") + counter;
        stats().count(bad);
        log().warn_throttled(bad, "topic '", reader.name(), "': ", error.what(), "; skipped (counted as ", bad, ")");
      }
    }
  };
  apply(*calibration_reader_, "calibrations", [&](const msg::StereoCalibration& message) {
    auto rectifier = std::make_shared<const StereoRectifier>(messages::to_calibration(message));
    log().info("calibration: raw ", rectifier->raw_size().width, "x", rectifier->raw_size().height,
               " pixels, rectified bf ", rectifier->camera().bf(), " px m");
    const double nearest_m = rectifier->camera().bf() / options_.stereo.num_disparities;
    if (nearest_m >= options_.stereo.max_depth_m) {
      log().warn("stereo: the nearest depth ", options_.stereo.num_disparities, " disparities reach (bf / ",
                 options_.stereo.num_disparities, " = ", nearest_m, " m) is beyond stereo.max_depth_m (",
                 options_.stereo.max_depth_m,
                 " m): no point can be kept; raise stereo.num_disparities or max_depth_m "
                 "(config/occupancy/street.yaml: a wide-baseline camera outdoors)");
    }
    std::lock_guard<std::mutex> lock(mutex_);
    rectifier_ = std::move(rectifier);
  });
  apply(*keyframe_state_reader_, "keyframe_states", [&](const msg::KeyframeState& message) {
    if (message.id == 0) return;  // a version marker
    Job job;
    job.keyframe_id = message.id;
    if (message.culled) {
      job.kind = Job::Kind::kCull;
      culled_ids_.insert(message.id);
    } else {
      job.kind = Job::Kind::kPose;
      job.T_wc = messages::to_pose(message.T_wc);
      has_state_[message.id] = true;
    }
    push(std::move(job));
  });
  if (odometry_reader_) {
    apply(*odometry_reader_, "odometry", [&](const msg::Odometry& message) { on_odometry(message); });
  }
  apply(*frame_reader_, "frames", [&](const msg::StereoFrame& message) { on_frame(message); });
  apply(*keyframe_reader_, "keyframes", [&](const msg::Keyframe& message) { on_keyframe(message); });
  match_pending();
  // After this pass's frames and keyframes: the saved map has every keyframe whose cloud was queued.
  for (auto& received : save_reader_->take()) {
    if (!received.info.valid_data) continue;
    Job job;
    job.kind = Job::Kind::kSave;
    job.request_id = received.sample->request_id;
    job.stem = received.sample->output_stem != nullptr ? received.sample->output_stem : "";
    stats().count("save_requests");
    push(std::move(job));
  }
}

void OccupancyNode::on_odometry(const msg::Odometry& message) {
  if (!message.gravity_valid) return;
  const Eigen::Vector3d g_w(message.g_w[0], message.g_w[1], message.g_w[2]);
  if (!g_w.allFinite() || g_w.norm() < 5.0 || g_w.norm() > 15.0) {
    throw std::runtime_error("frame seq " + std::to_string(message.seq) +
                             ": gravity g_w is not finite or not 5..15 m/s^2");
  }
  latest_up_w_ = -g_w.normalized();
  // The worker turns the grid (and fuses every cloud again) only when gravity moved by more than this
  // since the last turn: the initialization's estimate is refined for a while in small steps.
  constexpr double kMinUpChangeRad = 0.2 * std::numbers::pi / 180.0;
  if (sent_up_w_ && std::acos(std::clamp(sent_up_w_->dot(*latest_up_w_), -1.0, 1.0)) <= kMinUpChangeRad) return;
  send_up(*latest_up_w_);
}

void OccupancyNode::send_up(const Eigen::Vector3d& up_w) {
  Job job;
  job.kind = Job::Kind::kUp;
  job.up_w = up_w;
  sent_up_w_ = up_w;
  push(std::move(job));
}

void OccupancyNode::on_frame(const msg::StereoFrame& message) {
  const messages::GreyPair images = messages::to_grey_images(message);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (rectifier_ && images.left.size() != rectifier_->raw_size()) {
      throw std::runtime_error("frame seq " + std::to_string(message.seq) + ": " + std::to_string(images.left.cols) +
                               "x" + std::to_string(images.left.rows) + " pixels, the calibration says " +
                               std::to_string(rectifier_->raw_size().width) + "x" +
                               std::to_string(rectifier_->raw_size().height));
    }
  }
  ring_.push_back(Frame{message.stamp_ns, images.left.clone(), images.right.clone()});
  while (static_cast<int>(ring_.size()) > options_.frame_ring) ring_.pop_front();
}

void OccupancyNode::on_keyframe(const msg::Keyframe& message) {
  const std::uint64_t id = message.id;
  first_poses_.emplace(id, messages::to_pose(message.T_wc));
  if (!has_state_.count(id)) {
    Job job;
    job.kind = Job::Kind::kPose;
    job.keyframe_id = id;
    job.T_wc = messages::to_pose(message.T_wc);
    push(std::move(job));
  }
  if (seen_keyframes_.count(id)) return;  // sent again (a restarted frontend), or its cloud was loaded
  seen_keyframes_[id] = true;
  pending_.push_back({id, message.stamp_ns, messages::to_pose(message.T_wc)});
}

void OccupancyNode::match_pending() {
  {
    // Without a calibration a cloud cannot be made: the keyframes wait (their frames stay in the ring
    // for frame_ring frames), as the frames' and the calibration's writers may match in either order.
    std::lock_guard<std::mutex> lock(mutex_);
    if (!rectifier_) return;
  }
  for (auto it = pending_.begin(); it != pending_.end();) {
    const auto frame =
        std::find_if(ring_.begin(), ring_.end(), [&](const Frame& f) { return f.stamp_ns == it->stamp_ns; });
    if (frame != ring_.end()) {
      Job job;
      job.kind = Job::Kind::kCloud;
      job.keyframe_id = it->id;
      job.frame = *frame;
      job.T_wc = it->T_wc;
      push(std::move(job));
      it = pending_.erase(it);
    } else if (!ring_.empty() && ring_.back().stamp_ns > it->stamp_ns) {
      // Newer frames arrived and its own is not among them: lost (dropped, or before a restart).
      stats().count("keyframes_without_frame");
      log().warn_throttled("keyframes_without_frame", "keyframe ", it->id, " (stamp ", it->stamp_ns,
                           " ns): its frame is not among the frames received; skipped (counted as "
                           "keyframes_without_frame)");
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
}

void OccupancyNode::push(Job job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(job));
  }
  wake_.notify_all();
}

void OccupancyNode::worker_loop() {
  if (options_.idle_priority) {
    // This thread only; the DDS thread that copies frames stays at the process's priority. OpenCV's
    // pool threads would not inherit it (the pool may start on another thread): OpenCV's work stays on
    // this one.
    cv::setNumThreads(1);
    const sched_param param{};
    if (const int error = pthread_setschedparam(pthread_self(), SCHED_IDLE, &param); error != 0) {
      log().warn("idle_priority: SCHED_IDLE refused (", std::strerror(error), "); the worker runs at normal priority");
    }
  }
  try {
    const auto period =
        std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options_.rebuild_period_s));
    Clock::time_point last_rebuild = Clock::now();
    for (;;) {
      std::optional<Job> job;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait_for(lock, kWaitPeriod, [&] { return stop_ || !jobs_.empty(); });
        if (!jobs_.empty()) {
          job = std::move(jobs_.front());
          jobs_.pop_front();
        } else if (stop_) {
          break;
        }
      }
      if (job) {
        switch (job->kind) {
          case Job::Kind::kCloud: make_cloud(*job); break;
          case Job::Kind::kPose:
            if (!map_->set_pose(job->keyframe_id, job->T_wc)) {
              stats().count("bad_poses");
              log().warn_throttled("bad_poses", "keyframe ", job->keyframe_id,
                                   ": non-finite pose; skipped (counted as bad_poses)");
            }
            break;
          case Job::Kind::kSave: save_on_request(*job); break;
          case Job::Kind::kUp: {
            if (!up_w_) {
              log().info("grid up: against the odometry's gravity, ", up_tilt_deg(job->up_w), " deg from ",
                         to_string(options_.map.up), "; the map is fused again in that frame");
            }
            map_->set_up_direction(job->up_w);  // drops the voxels: fuse_pending() fuses every cloud again
            up_w_ = job->up_w;
            ++up_changes_;
            stats().count("grid_up_changes");
            grid_dirty_ = cloud_dirty_ = true;
            break;
          }
          case Job::Kind::kCull:
            if (map_->has_cloud(job->keyframe_id)) grid_dirty_ = cloud_dirty_ = true;
            map_->cull(job->keyframe_id);
            if (!options_.state_dir.empty()) std::filesystem::remove(cloud_file(options_.state_dir, job->keyframe_id));
            stats().count("keyframes_culled");
            break;
        }
      }
      bool idle = false;
      bool stopping = false;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        idle = jobs_.empty();
        stopping = stop_;
      }
      // Moved keyframes: fused again when no work waits (a cloud first), at most once a period; not
      // once the process stops, whose final rebuild fuses everything anyway (on the room's 92 clouds
      // with the TSDF a rebuild here took 44 s of the end's 116 s).
      if (idle && !stopping && map_->stale() && Clock::now() - last_rebuild >= period) {
        auto timer = stats().time("rebuild");
        map_->rebuild();
        last_rebuild = Clock::now();
        stats().count("rebuilds");
        grid_dirty_ = cloud_dirty_ = true;
      }
      if (!stopping) {
        // Timed only when it fused something: the loop also passes here for poses and idle wake-ups.
        // Stopping, the clouds still queued are made but not fused one by one: the final rebuild does.
        const std::size_t fused_before = map_->fused();
        const Clock::time_point start = Clock::now();
        const double cpu_start_ms = thread_cpu_ms();
        map_->fuse_pending();
        if (map_->fused() != fused_before) {
          grid_dirty_ = cloud_dirty_ = true;
          stats().record_ms("fusion", std::chrono::duration<double, std::milli>(Clock::now() - start).count());
          stats().record_ms("fusion_cpu", thread_cpu_ms() - cpu_start_ms);
        }
      }
      if (idle) publish_live(/*final=*/false);
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    worker_error_ = std::current_exception();
    runtime::request_shutdown();
  }
}

void OccupancyNode::make_cloud(const Job& job) {
  std::shared_ptr<const StereoRectifier> rectifier;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    rectifier = rectifier_;
  }
  if (!rectifier) {
    stats().count("keyframes_without_calibration");
    log().warn_throttled("keyframes_without_calibration", "keyframe ", job.keyframe_id,
                         ": no calibration received yet; skipped (counted as keyframes_without_calibration)");
    return;
  }
  if (job.frame.left.size() != rectifier->raw_size() || job.frame.right.size() != rectifier->raw_size()) {
    stats().count("bad_frame_size");
    log().warn_throttled("bad_frame_size", "keyframe ", job.keyframe_id, ": frame of ", job.frame.left.cols, "x",
                         job.frame.left.rows, " pixels, the calibration says ", rectifier->raw_size().width, "x",
                         rectifier->raw_size().height, "; skipped (counted as bad_frame_size)");
    return;
  }
  if (!stereo_ || stereo_->camera().width_px != rectifier->camera().width_px ||
      stereo_->camera().fx_px != rectifier->camera().fx_px || stereo_->camera().bf() != rectifier->camera().bf()) {
    stereo_.emplace(rectifier->camera(), options_.stereo);
    multiview_.reset();
    if (options_.multiview.enabled()) {
      multiview_.emplace(rectifier->camera(), options_.multiview);
      restore_views();
    }
  }
  KeyframeCloud cloud;
  cloud.stamp_ns = job.frame.stamp_ns;
  {
    const double cpu_start_ms = thread_cpu_ms();
    auto timer = stats().time("disparity");
    cv::Mat left, right;
    rectifier->rectify(job.frame.left, job.frame.right, left, right);
    // HE as the frontend applies it (one mapping for the pair), so SGBM matches what ORB saw.
    equalizer_->equalize(left, right, left, right);
    // Normals only for the TSDF (its distance to the point's plane); sigma for both fusion models.
    const bool normals = options_.map.voxels.model == FusionModel::kTsdf;
    cv::Mat disparity = stereo_->disparity(left, right);
    if (multiview_ && job.T_wc.matrix().allFinite()) {
      // Refined against the previous keyframes' left images, then kept as one of them.
      auto multiview_timer = stats().time("multiview");
      MultiViewDepthStats refined;
      disparity = multiview_->refine(disparity, left, right, job.T_wc, &refined);
      multiview_->add_view(left, job.T_wc);
      keep_view(job.keyframe_id, left, job.T_wc);
      if (refined.views_used > 0) {
        ++multiview_keyframes_;
        multiview_pixels_ += refined.pixels;
        multiview_refined_ += refined.refined;
        stats().count("multiview_keyframes");
      }
    }
    stereo_->cloud_from_disparity(disparity, cloud.points_c, normals ? &cloud.normals_c : nullptr);
    cloud.sigma_per_m2 = stereo_->sigma_per_m2();
    stats().record_ms("disparity_cpu", thread_cpu_ms() - cpu_start_ms);
  }
  // Persisted before it is counted: a process whose status shows N clouds has N clouds on disk.
  if (!options_.state_dir.empty()) write_cloud(cloud_file(options_.state_dir, job.keyframe_id), job.keyframe_id, cloud);
  stats().count("clouds");
  map_->add_cloud(job.keyframe_id, std::move(cloud));
}

void OccupancyNode::save_on_request(const Job& job) {
  std::string problem;
  const std::filesystem::path stem = job.stem.empty() ? options_.output_stem : job.stem;
  if (stem.empty()) {
    problem = "no output stem: the request names none and the process has no --output-stem";
  } else if (!stem.is_absolute()) {
    problem = "output stem '" + stem.string() + "' is not absolute (heslam-occupancy-save makes it so)";
  }
  // The map as it is now: the clouds queued before the request, at the keyframes' current poses.
  map_->fuse_pending();
  if (problem.empty() && map_->fused() == 0) problem = "no keyframe cloud fused yet";
  OccupancyGrid grid;
  std::size_t points = 0;
  if (problem.empty()) {
    try {
      auto timer = stats().time("save");
      if (map_->stale()) {
        map_->rebuild();
        grid_dirty_ = cloud_dirty_ = true;
      }
      grid = map_->grid();
      std::filesystem::path ply = stem;
      ply += ".ply";
      grid.write_map_server(stem);
      points = map_->write_ply(ply);
    } catch (const std::exception& error) {
      problem = error.what();
    }
  }
  msg::OccupancySaveReply reply{};
  reply.schema_version = msg::kSchemaVersion;
  reply.request_id = job.request_id;
  reply.ok = problem.empty();
  const std::string stem_text = stem.string();
  reply.output_stem = const_cast<char*>(stem_text.c_str());
  reply.keyframes = static_cast<std::uint32_t>(map_->fused());
  reply.occupied_cells = static_cast<std::uint32_t>(reply.ok ? grid.count(CellState::kOccupied) : 0);
  reply.free_cells = static_cast<std::uint32_t>(reply.ok ? grid.count(CellState::kFree) : 0);
  reply.points = static_cast<std::uint32_t>(points);
  reply.message = const_cast<char*>(problem.c_str());
  save_writer_->write(reply);
  if (reply.ok) {
    stats().count("saves");
    log().info("saved on request ", job.request_id, ": ", stem_text, ".pgm/.yaml/.ply (", reply.keyframes,
               " keyframe clouds, ", reply.occupied_cells, " occupied + ", reply.free_cells, " free cells, ", points,
               " points)");
  } else {
    stats().count("saves_failed");
    log().warn("save request ", job.request_id, ": ", problem, "; nothing written (counted as saves_failed)");
  }
}

void OccupancyNode::write_outputs() {
  {
    auto timer = stats().time("final_rebuild");
    map_->rebuild();
  }
  const OccupancyGrid grid = map_->grid();
  const std::size_t occupied = grid.count(CellState::kOccupied);
  const std::size_t free = grid.count(CellState::kFree);
  const double area_m2 = static_cast<double>(occupied + free) * grid.resolution_m() * grid.resolution_m();
  log().info("map: ", map_->fused(), " keyframe clouds fused (", map_->cloud_points(), " points), ",
             map_->voxels().size(), " voxels (", map_->voxels().memory_bytes() / 1024, " KiB), grid ", occupied,
             " occupied + ", free, " free cells (", area_m2, " m^2)");
  if (options_.multiview.enabled()) {
    log().info("multi-view: ", multiview_keyframes_, " keyframes refined against earlier keyframes, ",
               multiview_refined_, " of their ", multiview_pixels_, " pixels refined");
  }
  if (map_->fused() == 0) {
    throw std::runtime_error("no keyframe cloud was fused (keyframes received: " +
                             std::to_string(seen_keyframes_.size()) + "); no map written");
  }
  grid_dirty_ = cloud_dirty_ = true;
  publish_live(/*final=*/true);
  if (options_.output_stem.empty()) return;
  grid.write_map_server(options_.output_stem);
  std::filesystem::path ply = options_.output_stem;
  ply += ".ply";
  const std::size_t points = map_->write_ply(ply);
  log().info("wrote ", options_.output_stem.string(), ".pgm/.yaml (map_server) and ", ply.string(), " (", points,
             " points)");
  if (up_w_) {
    log().info("grid up: against the last gravity, ", up_tilt_deg(*up_w_), " deg from ", to_string(options_.map.up),
               " (", up_changes_, " turns)");
  }
  if (options_.first_poses_grid) write_first_poses_grid();
}

double OccupancyNode::up_tilt_deg(const Eigen::Vector3d& up_w) const {
  const double cosine = std::clamp(up_w.dot(up_direction(options_.map.up)), -1.0, 1.0);
  return std::acos(cosine) * 180.0 / std::numbers::pi;
}

void OccupancyNode::write_first_poses_grid() {
  auto timer = stats().time("first_poses_rebuild");
  OccupancyMap before(options_.map);
  if (up_w_) before.set_up_direction(*up_w_);
  std::size_t without_pose = 0;
  double moved_max_m = 0.0;  // how far a keyframe's camera moved from its first pose to its final one
  for (const auto& [id, cloud] : map_->all_clouds()) {
    if (map_->culled(id)) continue;
    const auto first = first_poses_.find(id);
    if (first == first_poses_.end() || !before.set_pose(id, first->second)) {
      ++without_pose;
      continue;
    }
    const auto now = map_->poses().find(id);
    if (now != map_->poses().end()) {
      moved_max_m = std::max(moved_max_m, (now->second.translation() - first->second.translation()).norm());
    }
    before.add_cloud(id, cloud);
  }
  before.rebuild();
  std::filesystem::path stem = options_.output_stem;
  stem += ".first_poses";
  const OccupancyGrid grid = before.grid();
  grid.write_map_server(stem);
  log().info("wrote ", stem.string(), ".pgm/.yaml: ", before.fused(), " keyframe clouds at their first poses (",
             without_pose, " without one; the farthest moved ", moved_max_m, " m since), grid ",
             grid.count(CellState::kOccupied), " occupied + ", grid.count(CellState::kFree), " free cells");
}

void OccupancyNode::restore_views() {
  // The views a killed process had kept, oldest first (the order of add_view), of this camera's size.
  std::sort(loaded_views_.begin(), loaded_views_.end(),
            [](const KeptView& a, const KeptView& b) { return a.sequence < b.sequence; });
  std::size_t restored = 0;
  for (const KeptView& view : loaded_views_) {
    if (view.left.cols != stereo_->camera().width_px || view.left.rows != stereo_->camera().height_px) {
      stats().count("bad_state_files");
      log().warn("kept view of keyframe ", view.keyframe_id, ": ", view.left.cols, "x", view.left.rows,
                 " pixels, the camera has ", stereo_->camera().width_px, "x", stereo_->camera().height_px,
                 "; skipped (counted as bad_state_files)");
      continue;
    }
    multiview_->add_view(view.left, view.T_wc);
    kept_views_.push_back({view.sequence, view.keyframe_id});
    ++restored;
  }
  if (restored > 0) log().info("multi-view: ", restored, " kept view(s) restored from the state folder");
  loaded_views_.clear();
}

void OccupancyNode::keep_view(std::uint64_t keyframe_id, const cv::Mat& left, const Pose3& T_wc) {
  if (options_.state_dir.empty()) return;
  // Persisted as the process keeps it (before the keyframe's cloud), the oldest beyond `neighbours` removed.
  const std::uint64_t sequence = next_view_sequence_++;
  write_view(view_file(options_.state_dir, keyframe_id), KeptView{keyframe_id, sequence, left, T_wc});
  kept_views_.push_back({sequence, keyframe_id});
  while (static_cast<int>(kept_views_.size()) > options_.multiview.neighbours) {
    std::filesystem::remove(view_file(options_.state_dir, kept_views_.front().keyframe_id));
    kept_views_.pop_front();
  }
}

void OccupancyNode::publish_live(bool final) {
  const Clock::time_point now = Clock::now();
  auto due = [&](Clock::time_point sent, double period_s) {
    return final || now - sent >= std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s));
  };
  if (map_->fused() == 0) return;
  std::int64_t newest_stamp_ns = 0;
  for (const auto& [id, cloud] : map_->all_clouds()) newest_stamp_ns = std::max(newest_stamp_ns, cloud.stamp_ns);
  const auto keyframes = static_cast<std::uint32_t>(map_->fused());
  Pose3 T_wg = Pose3::Identity();
  T_wg.linear() = map_->R_gw().transpose();
  if (grid_dirty_ && due(grid_sent_, options_.grid_period_s)) {
    auto timer = stats().time("grid_publish");
    OccupancyGrid grid = map_->grid();
    grid_dirty_ = false;
    grid_sent_ = now;
    // Republished when it changed (a rebuild at the same poses often gives the same cells); the final
    // one always, so a reader that saw every revision ends on the saved grid.
    if (final || !published_grid_ || published_grid_->cells() != grid.cells()) {
      grid_writer_->write(GridMessage(grid, T_wg, ++grid_revision_, newest_stamp_ns, keyframes).get());
      stats().count("grids_published");
      published_grid_ = std::move(grid);
    }
  }
  if (cloud_writer_ && cloud_dirty_ && due(cloud_sent_, options_.cloud_period_s)) {
    auto timer = stats().time("cloud_publish");
    cloud_dirty_ = false;
    cloud_sent_ = now;
    std::vector<Eigen::Vector3f> points_w;
    points_w.reserve(map_->cloud_points());
    for (const auto& [id, cloud] : map_->all_clouds()) {
      const auto pose = map_->poses().find(id);
      if (pose == map_->poses().end()) continue;
      const Eigen::Matrix3f R = pose->second.rotation().cast<float>();
      const Eigen::Vector3f t = pose->second.translation().cast<float>();
      for (const Eigen::Vector3f& p : cloud.points_c) points_w.push_back(R * p + t);
    }
    const auto total = static_cast<std::uint32_t>(points_w.size());
    cloud_writer_->write(CloudMessage(decimate(points_w, static_cast<std::size_t>(options_.cloud_max_points)), total,
                                      ++cloud_revision_, newest_stamp_ns, keyframes)
                             .get());
    stats().count("clouds_published");
  }
  if (final) {
    // Latched, but this process is about to exit: give matched readers (the bridge, the viewer) a
    // bounded moment to acknowledge the final map.
    constexpr dds_duration_t kFinalAckTimeout = DDS_SECS(2);
    dds_wait_for_acks(grid_writer_->handle(), kFinalAckTimeout);
    if (cloud_writer_) dds_wait_for_acks(cloud_writer_->handle(), kFinalAckTimeout);
  }
}

}  // namespace heslam::occupancy
