// A loop closer process's DDS side (see loop_closer_node.hpp).
#include "components/loop_closer/loop_closer_node.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstddef>
#include <cstdio>
#include <ctime>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/map/ids.hpp"
#include "components/core/map/point_ids_digest.hpp"
#include "components/core/mapping/map_file.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/loop_correction.hpp"
#include "components/messages/map_state.hpp"
#include "runtime/heap.hpp"
#include "runtime/run_id.hpp"
#include "runtime/run_journal.hpp"
#include "runtime/sequence.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::loop_closer {
namespace {

// How long a keyframe of another agent's map waits for the mapper's state of that map before the agent
// guard refuses it (the states topic of a restarted loop closer matches within discovery's ~1 s).
constexpr std::chrono::seconds kAwaitMapState{3};

// Wait granularity of the main loop: shutdown is also signalled through the waitset, this only
// bounds how long a missed wake-up could delay it.
constexpr std::chrono::milliseconds kWaitPeriod{200};
// KeyframeDone of a second writer of a role kept while its predecessor still counts as matched.
constexpr std::ptrdiff_t kMaxHeldKeyframeDone = 64;
// While a real-time global BA runs: how often to look whether it finished (nothing wakes the waitset).
constexpr std::chrono::milliseconds kGlobalBaPoll{20};
// Before the first KeyframeDone: how long to wait for the lockstep reader (the frontend) to match.
constexpr std::chrono::milliseconds kReaderWait{2000};
// Correction ids: the creator tag in the top byte (map.hpp) and, below, a start value from the clock
// so a restarted loop closer without a state file never reuses an id the mapper already applied.
constexpr int kClockShiftBits = 20;
// Keyframes of a second writer kept in case it takes over (a restarted frontend; ~60 KB each).
constexpr std::size_t kHeldKeyframes = 64;
// What the state file holds; a file of another format is not resumed from.
constexpr const char* kStateFileFormat = "heslam-loop-closer-state 2";
// Inertial runs: how long a keyframe waits for the odometry of its frame (the frontend writes it right
// after the keyframe, so it is there long before the mapper's acknowledgement); then it goes on with
// the newest gravity before it (counted).
constexpr std::chrono::milliseconds kOdometryWait{2000};
// A gravity outside this range (m/s^2) is not one (the Earth's is 9.78..9.83).
constexpr double kMinGravityM_S2 = 5.0;
constexpr double kMaxGravityM_S2 = 15.0;
constexpr double kEarthGravityM_S2 = 9.81;  // InertialInitOptions::gravity_m_s2, the frontend's
// Gravity samples kept by stamp (those before the last processed keyframe's are dropped as it goes).
constexpr std::size_t kMaxGravitySamples = 4096;
// Odometry samples of a second writer kept in case it takes over (a restarted frontend).
constexpr std::size_t kHeldOdometry = 64;

std::uint64_t clock_counter_start() {
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  const auto ns = static_cast<std::uint64_t>(now.tv_sec) * 1000000000ULL + static_cast<std::uint64_t>(now.tv_nsec);
  return (ns >> kClockShiftBits) & ((std::uint64_t{1} << 48) - 1);
}

}  // namespace

LoopCloserNode::LoopCloserNode(std::string default_name, const runtime::CommonArgs& args)
    : Component(std::move(default_name), args) {}

void LoopCloserNode::configure(const runtime::Config& config) {
  options_ = LoopCloserProcessOptions::from_config(config, args().rest);
  detector_ = make_detector(config, options_);
  waitset_ = std::make_unique<runtime::WaitSet>(participant());
  runtime::CheckedReaderOptions keyframe_options = messages::checked_options<msg::Keyframe>(kHeldKeyframes);
  if (options_.agents > 1) {
    // Several frontends write map/keyframes: each is held to its agent's ids instead (take_all).
    keyframe_options.single_writer = false;
    agent_guard_.emplace(options_.agents);
  }
  keyframe_reader_.emplace(participant(), topics().keyframes(), log(), stats(), nullptr, keyframe_options);
  keyframe_state_reader_.emplace(participant(), topics().keyframe_states(), log(), stats(), nullptr,
                                 messages::checked_options<msg::KeyframeState>(messages::kMapStateHeld));
  point_state_reader_.emplace(participant(), topics().map_points(), log(), stats(), nullptr,
                              messages::checked_options<msg::MapPointState>(messages::kMapStateHeld));
  keyframe_done_reader_.emplace(participant(), topics().keyframe_done());
  if (options_.gravity_from_odometry) {
    odometry_reader_.emplace(participant(), topics().odometry(), log(), stats(),
                             messages::sample_check<msg::Odometry>(),
                             messages::checked_options<msg::Odometry>(kHeldOdometry));
  }
  const bool inertial_possible = options_.gravity_from_odometry || options_.closing.correction.pose_graph.four_dof;
  if (options_.global_bundle_adjustment && options_.global_ba_imu && inertial_possible) {
    imu_input_.emplace(participant(), topics(), log(), stats(), messages::ImuInput::Camera::kNeeded);
    ImuBufferOptions buffer_options;
    buffer_options.source = imu_input_->readings_topic();
    imu_buffer_ = std::make_unique<ImuBuffer>(buffer_options);
    imu_input_->feed(*imu_buffer_);
    imu_input_->attach(*waitset_);
  }
  keyframe_done_roles_.emplace(log(), stats(), keyframe_done_reader_->name());
  waitset_->attach(*keyframe_reader_);
  waitset_->attach(*keyframe_state_reader_);
  waitset_->attach(*point_state_reader_);
  waitset_->attach(*keyframe_done_reader_);
  if (odometry_reader_) waitset_->attach(*odometry_reader_);
  correction_writer_.emplace(participant(), topics().loop_corrections());
  keyframe_done_writer_.emplace(participant(), topics().keyframe_done());
  correction_counter_ = clock_counter_start();
  load_mapper_map();
  load_state();
  if (runtime::RunEndWatch::joined_by_hand()) run_end_.emplace(participant(), topics());
  // Under a supervisor the pipeline file says --real-time exactly for real-time runs; joined by hand,
  // the run's mode is not known here.
  const char* inline_ba =
      run_end_ ? "on (inline, each keyframe waits for it; --real-time for a real-time run)" : "on (lockstep)";
  log().info(
      "detector ", detector_->name(), ", global BA ",
      options_.global_bundle_adjustment ? (options_.real_time ? "on (own thread, real time)" : inline_ba) : "off",
      options_.state_file.empty() ? ", no state file" : ", state file " + options_.state_file.string(),
      options_.closing.correction.pose_graph.four_dof ? ", 4-DoF pose graph"
      : options_.gravity_from_odometry                ? ", 4-DoF pose graph once the odometry carries gravity"
                                                      : "",
      imu_input_ ? ", global BA with IMU factors in inertial runs" : "");
}

void LoopCloserNode::run() {
  while (!shutdown_requested()) {
    if (waitset_->wait(global_ba_.running() ? kGlobalBaPoll : kWaitPeriod) == runtime::Wake::kShutdown) break;
    log().flush_throttled(/*due_only=*/true);
    take_all();
    process_ready_keyframes();
    if (global_ba_.finished()) finish_global_ba();
    if (const std::optional<std::string> ended = run_end_ ? run_end_->poll() : std::nullopt) {
      log().info(*ended, "; exiting");
      break;
    }
    if (run_end_ && !run_supervisor_seen_ && !run_end_->supervisor_name().empty()) {
      run_supervisor_seen_ = true;
      log().info("joined run ", runtime::process_run_id(), " of ", run_end_->supervisor_name(), ": exits when it ends");
    }
  }
  if (global_ba_.abort()) stats().count("global_ba_aborted");
  log().flush_throttled();
  log_summary();
}

std::size_t LoopCloserNode::take_all() {
  std::size_t taken = 0;
  // The keyframes are admitted after the mapper's states taken with them: the agent guard's "the map
  // exists" is the mapper's word, and a restarted loop closer gets another agent's keyframes of a merged
  // map and the states that say the map exists in any order (the mirror takes either first).
  std::vector<runtime::Received<msg::Keyframe>> keyframes = keyframe_reader_->take();
  // The state readers are drained until empty before the version markers taken meanwhile count
  // (messages::MirrorVersion).
  messages::MirrorVersion markers;
  for (std::size_t batch = 1; batch != 0;) {
    batch = 0;
    for (auto& received : keyframe_state_reader_->take()) {
      ++batch;
      if (!received.info.valid_data) continue;
      if (messages::is_version_marker(*received.sample)) {
        markers.keyframe_states = std::max(markers.keyframe_states, received.sample->map_version);
        continue;
      }
      try {
        mirror_.apply_keyframe_state(*received.sample);
      } catch (const std::exception& error) {
        stats().count("bad_keyframe_states");
        log().warn_throttled("bad_keyframe_states", "topic '", topics().keyframe_states().name, "': ", error.what(),
                             "; skipped");
      }
    }
    for (auto& received : point_state_reader_->take()) {
      ++batch;
      if (!received.info.valid_data) {
        if (received.info.disposed && received.sample->id != messages::kVersionMarkerId) {
          mirror_.point_disposed(received.sample->id);
        }
        continue;
      }
      if (messages::is_version_marker(*received.sample)) {
        markers.point_states = std::max(markers.point_states, received.sample->map_version);
        continue;
      }
      try {
        mirror_.apply_point_state(*received.sample);
      } catch (const std::exception& error) {
        stats().count("bad_point_states");
        log().warn_throttled("bad_point_states", "topic '", topics().map_points().name, "': ", error.what(),
                             "; skipped");
      }
    }
    taken += batch;
  }
  // Those held for their map's state first (a restarted loop closer: the keyframes topic may match
  // before the states topic), then the new ones, each once.
  const auto now = std::chrono::steady_clock::now();
  std::vector<KeyframeAwaitingMap> candidates = std::move(awaiting_map_);
  awaiting_map_.clear();
  for (auto& received : keyframes) {
    ++taken;
    if (received.info.valid_data) candidates.push_back({std::move(received), now});
  }
  for (KeyframeAwaitingMap& candidate : candidates) {
    if (agent_guard_) {
      const Admission admission = admit_agent_keyframe(candidate, now);
      if (admission == Admission::kWait) awaiting_map_.push_back(std::move(candidate));
      if (admission != Admission::kAdmitted) continue;
    }
    try {
      mirror_.add_keyframe(*candidate.received.sample);
    } catch (const std::exception& error) {
      stats().count("bad_keyframes");
      log().warn_throttled("bad_keyframes", "topic '", topics().keyframes().name, "': ", error.what(), "; skipped");
    }
  }
  mirror_.count_markers(markers);
  take_odometry();
  take_imu();
  for (auto& received : keyframe_done_reader_->take()) {
    ++taken;
    if (!received.info.valid_data) continue;
    // Another run's mapper on the domain must not acknowledge our corrections.
    if (!runtime::writer_of_this_run(keyframe_done_reader_->handle(), received.info.publication_handle)) continue;
    const msg::KeyframeDone& done = *received.sample;
    const std::string component = runtime::to_string(done.component);
    if (component == name()) continue;  // our own acknowledgements
    held_keyframe_done_.push_back(
        {received.info.publication_handle, component, done.keyframe_id, done.map_version, done.correction_id});
  }
  // Each taken one is asked about once as new; those held are asked again until their writer takes
  // its role over (its predecessor left) or is refused.
  std::vector<HeldKeyframeDone> still_held;
  for (const HeldKeyframeDone& done : held_keyframe_done_) {
    const runtime::RoleBinding::Claim claim = keyframe_done_roles_->claim(
        keyframe_done_reader_->handle(), done.component, done.writer, done.subject(), done.held);
    if (claim == runtime::RoleBinding::Claim::kHeld) {
      still_held.push_back(done);
      still_held.back().held = true;
      continue;
    }
    if (claim != runtime::RoleBinding::Claim::kAccepted) continue;
    if (done.correction_id != 0) {
      corrections_applied_[done.correction_id] = done.map_version;
    } else {
      mapped_[done.keyframe_id] = done.map_version;
    }
  }
  if (std::ssize(still_held) > kMaxHeldKeyframeDone)
    still_held.erase(still_held.begin(), still_held.end() - kMaxHeldKeyframeDone);
  held_keyframe_done_ = std::move(still_held);
  return taken;
}

LoopCloserNode::Admission LoopCloserNode::admit_agent_keyframe(const KeyframeAwaitingMap& candidate,
                                                               std::chrono::steady_clock::time_point now) {
  const msg::Keyframe& message = *candidate.received.sample;
  const dds_instance_handle_t writer = candidate.received.info.publication_handle;
  if (!runtime::writer_of_this_run(keyframe_reader_->handle(), writer)) {
    stats().count(runtime::kSecondWriterSamples);
    return Admission::kRefused;
  }
  const auto map_exists = [this](MapId map_id) { return mirror_.knows_map(map_id); };
  const std::optional<std::string> problem = agent_guard_->check(writer, message.id, message.map_id, map_exists);
  if (!problem) return Admission::kAdmitted;
  // Refused only for its map: the mapper's states that say the map exists may still be on their way
  // (another agent's keyframes of a merged map, replayed to a restarted loop closer); held a while.
  const bool only_the_map = !agent_guard_->check(writer, message.id, message.map_id, [](MapId) { return true; });
  if (only_the_map && now - candidate.since < kAwaitMapState) return Admission::kWait;
  stats().count("refused_agent_keyframes");
  log().warn_throttled("refused_agent_keyframes", "topic '", keyframe_reader_->name(), "': ", *problem,
                       "; refused (counted as refused_agent_keyframes)");
  refused_.insert(message.id);
  acknowledge(message.id);  // its lockstep frontend must not wait for a keyframe we will not process
  return Admission::kRefused;
}

void LoopCloserNode::process_ready_keyframes() {
  // In keyframe order, each once the mirror holds it and the map state the mapper acknowledged.
  while (!mapped_.empty() && !shutdown_requested()) {
    const auto [id, version] = *mapped_.begin();
    if (refused_.count(id) != 0) {  // refused by the agent guard (the mapper refuses it too)
      mapped_.erase(mapped_.begin());
      continue;
    }
    // Ids grow per creator, not across agents (ids.hpp): each agent's keyframes are compared with
    // the last processed keyframe of the same agent.
    const auto last = last_processed_.find(creator_of(id));
    if (last != last_processed_.end() && id <= last->second) {
      mapped_.erase(mapped_.begin());
      keyframe_done_roles_->done(id);
      // A restarted loop closer: the frontend may still wait for the last one.
      if (id == last->second) acknowledge(id);
      continue;
    }
    if (mirror_.map().keyframe(id) == nullptr || mirror_.map().version < version) return;  // in flight
    if (!odometry_covers(*mirror_.map().keyframe(id))) return;
    mapped_.erase(mapped_.begin());
    keyframe_done_roles_->done(id);
    process_keyframe(id);
    last_processed_[creator_of(id)] = id;
    save_state();
    acknowledge(id);
  }
}

void LoopCloserNode::process_keyframe(KeyframeId id) {
  stats().count("keyframes");
  if (!closing_) {
    if (!mirror_.camera()) return;  // unreachable: the mirror holds a keyframe, so it has its camera
    closing_ = std::make_unique<LoopClosing>(*mirror_.camera(), std::move(detector_), options_.closing);
    for (const auto& [loop_kf, matched_kf] : restored_loops_) closing_->add_loop_edge(loop_kf, matched_kf);
  }
  choose_pose_graph(id);
  const std::size_t awaiting_state = mirror_.keyframes_awaiting_state();
  LoopClosingResult result = closing_->process_keyframe(mirror_.map(), id);
  stats().record_ms("detection", result.timings.detection_ms);
  if (!result.candidates.keyframes.empty()) {
    stats().count("candidates", result.candidates.keyframes.size());
    stats().record_ms("verification", result.timings.verification_ms);
  } else {
    log().debug("keyframe ", format_id(id), ": no loop candidate (", result.candidates.reason, ")");
  }
  for (const LoopRejection& rejection : result.rejected) {
    stats().count("loops_rejected");
    log().debug("keyframe ", format_id(id), ": candidate ", format_id(rejection.candidate),
                " rejected: ", rejection.reason);
  }
  if (!result.correction) {
    result = process_merge(id);
    if (!result.correction) return;
  } else {
    stats().count("loops_accepted");
    if (closing_->pose_graph_options().four_dof) stats().count("four_dof_corrections");
    stats().record_ms("correction", result.timings.correction_ms);
  }
  // ORB-SLAM2: a new loop makes the running global BA stale; it restarts after this correction.
  if (global_ba_.abort()) {
    stats().count("global_ba_aborted");
    log().info("global BA aborted: a newer loop at keyframe ", format_id(id));
  }
  LoopCorrection correction = std::move(*result.correction);
  if (correction.kind == CorrectionKind::kMerge) {
    const Keyframe* query = mirror_.map().keyframe(id);
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%.6f", query != nullptr ? static_cast<double>(query->stamp_ns) * 1e-9 : 0.0);
    log().info("maps merged: map ", result.merged_map, " into map ", result.into_map, " at keyframe ", format_id(id),
               " (stamp ", stamp, " s): ", format_id(correction.loop_kf), " -> ", format_id(correction.matched_kf),
               " with ", result.loop_matches, " matches (", result.merge_found, "); ",
               result.merge_stats.moved_keyframes, " keyframes moved, ", correction.point_merges.size(),
               " points fused, ", result.merge_stats.seam_connections, " keyframe pairs joined across the seam, ",
               correction.corrected_T_wc.size(), " keyframes corrected in ", result.timings.merge_ms,
               " ms (map version ", mirror_.map().version, ")");
  } else {
    log().info("loop closed: keyframe ", format_id(id), " -> ", format_id(correction.matched_kf), " with ",
               result.loop_matches, " matches; correcting ", correction.corrected_T_wc.size(), " keyframes, merging ",
               correction.point_merges.size(), " points (map version ", mirror_.map().version, ", ", awaiting_state,
               " keyframes from the frontend left out: not mapped yet)");
  }
  if (!publish_and_wait(std::move(correction)) || !options_.global_bundle_adjustment) {
    release_heap("loop correction");
    return;
  }

  log().info("global BA started on map version ", mirror_.map().version, ": ", mirror_.map().keyframes.size(),
             " keyframes (", mirror_.keyframes_awaiting_state(), " more from the frontend left out: not mapped yet)");
  global_ba_.start(*closing_, mirror_.map(), id, inertial_input());
  if (!options_.real_time) finish_global_ba();
}

void LoopCloserNode::take_odometry() {
  if (!odometry_reader_) return;
  for (auto& received : odometry_reader_->take()) {
    if (!received.info.valid_data) continue;
    const msg::Odometry& odometry = *received.sample;
    newest_odometry_stamp_ = std::max(newest_odometry_stamp_, odometry.stamp_ns);
    if (!odometry.gravity_valid) continue;
    const Eigen::Vector3d g_w(odometry.g_w[0], odometry.g_w[1], odometry.g_w[2]);
    if (!g_w.allFinite() || !(g_w.norm() > kMinGravityM_S2 && g_w.norm() < kMaxGravityM_S2)) {
      stats().count("bad_gravities");
      log().warn_throttled("bad_gravities", "topic '", topics().odometry().name, "': frame ", odometry.seq,
                           ": field 'g_w' is not a gravity (finite, ", kMinGravityM_S2, "..", kMaxGravityM_S2,
                           " m/s^2); skipped");
      continue;
    }
    gravity_by_stamp_[odometry.stamp_ns] = g_w;
  }
  while (gravity_by_stamp_.size() > kMaxGravitySamples) gravity_by_stamp_.erase(gravity_by_stamp_.begin());
}

bool LoopCloserNode::odometry_covers(const Keyframe& keyframe) {
  // Only once the run is known to be inertial: stereo-only runs (and runs without a frontend) never wait.
  if (gravity_by_stamp_.empty() || newest_odometry_stamp_ >= keyframe.stamp_ns) {
    odometry_wait_since_.reset();
    return true;
  }
  const auto now = std::chrono::steady_clock::now();
  if (!odometry_wait_since_) odometry_wait_since_ = now;
  if (now - *odometry_wait_since_ < kOdometryWait && !shutdown_requested()) return false;
  odometry_wait_since_.reset();
  stats().count("odometry_wait_timeouts");
  log().warn_throttled("odometry_wait_timeouts", "keyframe ", format_id(keyframe.id), ": no odometry of its frame on '",
                       topics().odometry().name, "' within ", kOdometryWait.count(),
                       " ms; the pose graph uses the newest gravity before it");
  return true;
}

void LoopCloserNode::choose_pose_graph(KeyframeId id) {
  const Keyframe* keyframe = mirror_.map().keyframe(id);
  if (gravity_by_stamp_.empty() || keyframe == nullptr || !closing_) return;
  // The gravity of the keyframe's frame (or the newest before it): a lockstep run repeats.
  auto after = gravity_by_stamp_.upper_bound(keyframe->stamp_ns);
  if (after == gravity_by_stamp_.begin()) return;  // initialized after this keyframe's frame
  const Eigen::Vector3d gravity_w = std::prev(after)->second;
  gravity_by_stamp_.erase(gravity_by_stamp_.begin(), std::prev(after));  // keeps the one used
  closing_->use_four_dof_pose_graph(gravity_w);
  if (!four_dof_announced_) {
    four_dof_announced_ = true;
    log().info("inertial run: loop corrections use the 4-DoF pose graph about the odometry's gravity (", gravity_w.x(),
               ", ", gravity_w.y(), ", ", gravity_w.z(), ") m/s^2 from keyframe ", format_id(id));
  }
}

void LoopCloserNode::take_imu() {
  if (!imu_input_) return;
  imu_input_->take();
  // Bounded: readings older than imu_buffer_s before the newest covered stamp are dropped.
  const std::int64_t covered = imu_buffer_->covered_until_ns();
  const auto keep_ns = static_cast<std::int64_t>(options_.imu_buffer_s * 1e9);
  if (!imu_buffer_->empty() && covered > INT64_MIN + keep_ns) imu_buffer_->discard_before(covered - keep_ns);
}

std::optional<GlobalInertialInput> LoopCloserNode::inertial_input() {
  if (!imu_input_ || !closing_ || !closing_->pose_graph_options().four_dof) return std::nullopt;
  const auto warn_once = [&](const std::string& kind, const std::string& line) {
    stats().count("global_ba_visual_" + kind);
    if (imu_warned_.insert(kind).second) log().warn(line, " (said once; counted as global_ba_visual_", kind, ")");
  };
  take_imu();
  std::int64_t newest_stamp = INT64_MIN;
  for (const auto& [id, keyframe] : mirror_.map().keyframes) {
    if (!keyframe.culled) newest_stamp = std::max(newest_stamp, keyframe.stamp_ns);
  }
  const std::optional<ImuCalibration>& imu_calibration = imu_input_->calibration();
  const std::optional<Pose3>& T_B_rect = imu_input_->T_B_rect();
  const auto imu_stamp = [&] { return newest_stamp + (imu_calibration ? imu_calibration->time_offset_ns : 0); };
  if (!options_.real_time) {
    // Lockstep: the readings up to the newest keyframe are in flight at most (the source sends them
    // before its frame), so wait for them: the same readings every run.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                                 std::chrono::duration<double>(options_.imu_wait_s));
    while (!(T_B_rect && imu_calibration && imu_buffer_->covered_until_ns() >= imu_stamp()) && !imu_input_->ended() &&
           std::chrono::steady_clock::now() < deadline && !shutdown_requested()) {
      waitset_->wait(std::chrono::milliseconds(20));
      take_imu();
    }
  }
  if (!T_B_rect || !imu_calibration) {
    warn_once("no_calibration", std::string("global BA without IMU factors: no ") +
                                    (!T_B_rect ? "stereo calibration on '" + imu_input_->camera_topic()
                                               : "IMU calibration on '" + imu_input_->calibration_topic()) +
                                    "'");
    return std::nullopt;
  }
  if (imu_buffer_->covered_until_ns() < imu_stamp()) {
    warn_once("imu_behind", "global BA: the IMU on '" + imu_input_->readings_topic() + "' covers up to " +
                                std::to_string(imu_buffer_->covered_until_ns()) + " ns, not the newest keyframe (" +
                                std::to_string(imu_stamp()) + " ns): the keyframes after it get no IMU factor");
  }
  const Pose3 T_cb = T_B_rect->inverse() * imu_calibration->T_BS;
  // The odometry's gravity (m/s^2); a direction given by pose_graph.gravity_w (any length) gets Earth's.
  Eigen::Vector3d gravity_w = closing_->pose_graph_options().gravity_w;
  if (!(gravity_w.norm() > kMinGravityM_S2 && gravity_w.norm() < kMaxGravityM_S2)) {
    gravity_w = gravity_w.normalized() * kEarthGravityM_S2;
  }
  GlobalInertialChainOptions chain_options;
  chain_options.max_interval_s = options_.imu_max_interval_s;
  GlobalInertialChainReport report;
  GlobalInertialInput input =
      build_global_inertial_input(mirror_.map(), *imu_buffer_, T_cb, imu_calibration->time_offset_ns,
                                  imu_calibration->noise, gravity_w, chain_options, &report);
  log().info("global BA with IMU factors: ", report.intervals, " keyframe intervals (", report.not_covered,
             " without IMU readings, ", report.too_long, " longer than ", options_.imu_max_interval_s, " s",
             report.first_problem.empty() ? "" : "; first: " + report.first_problem, "), gyro bias guess (",
             report.gyro_bias_rad_s.x(), ", ", report.gyro_bias_rad_s.y(), ", ", report.gyro_bias_rad_s.z(), ") rad/s");
  if (input.intervals.empty()) {
    warn_once("no_intervals",
              "global BA without IMU factors: no two consecutive keyframes with IMU readings between "
              "them" +
                  (report.first_problem.empty() ? "" : " (" + report.first_problem + ")"));
    return std::nullopt;
  }
  return input;
}

LoopClosingResult LoopCloserNode::process_merge(KeyframeId id) {
  LoopClosingResult result = closing_->process_merge(mirror_.map(), id);
  if (!result.candidates.keyframes.empty()) {
    stats().count("merge_candidates", result.candidates.keyframes.size());
  }
  if (!result.candidates.reason.empty()) {
    log().debug("keyframe ", format_id(id), ": merge candidates ", result.candidates.keyframes.size(), " (",
                result.candidates.reason, ")");
  }
  for (const LoopRejection& rejection : result.rejected) {
    stats().count("merges_rejected");
    // A merge the gate refuses is worth a line: the maps stay apart.
    if (rejection.reason.rfind("merge gate:", 0) == 0) {
      log().info("keyframe ", format_id(id), ": merge with keyframe ", format_id(rejection.candidate),
                 " rejected: ", rejection.reason);
    } else {
      log().debug("keyframe ", format_id(id), ": merge candidate ", format_id(rejection.candidate),
                  " rejected: ", rejection.reason);
    }
  }
  if (result.correction) {
    stats().count("merges_accepted");
    stats().record_ms("merge", result.timings.merge_ms);
  }
  return result;
}

void LoopCloserNode::finish_global_ba() {
  BackgroundGlobalBa::Outcome outcome = global_ba_.collect();
  if (!outcome.correction) return;
  stats().record_ms("global_ba", outcome.elapsed_ms);
  stats().count("global_bundle_adjustments");
  stats().record_ms("global_ba_cpu", outcome.cpu_ms);
  if (outcome.stats.imu_factors > 0) {
    stats().count("global_ba_inertial");
    stats().count("global_ba_imu_factors", static_cast<std::uint64_t>(outcome.stats.imu_factors));
  }
  log().info("global BA for the loop at keyframe ", format_id(outcome.correction->loop_kf), ": ",
             outcome.correction->corrected_T_wc.size(), " keyframes, ", outcome.correction->corrected_points.size(),
             " points, ", outcome.stats.imu_factors, " IMU factors, ", outcome.stats.iterations, " iterations in ",
             outcome.elapsed_ms, " ms (CPU ", outcome.cpu_ms, " ms)");
  publish_and_wait(std::move(*outcome.correction));
  release_heap("global BA");
}

void LoopCloserNode::release_heap(const char* after) {
  const runtime::HeapRelease release = runtime::release_free_heap(&stats());
  log().info("heap after the ", after, ": ", release.released_bytes() / 1024, " KiB returned to the system in ",
             release.elapsed_ms, " ms, RSS ", release.rss_after_bytes / (1024 * 1024), " MiB");
}

bool LoopCloserNode::publish_and_wait(LoopCorrection correction) {
  correction.id = make_id(kLoopCloserTag, ++correction_counter_);
  const std::uint64_t id = correction.id;
  {
    const messages::LoopCorrectionMessage message(correction);
    if (correction_writer_->write(message.get()) == runtime::WriteResult::kTimeout) {
      stats().count("correction_write_timeouts");
      log().warn("loop correction ", format_id(id), ": write timed out (is the local mapper alive?)");
    }
  }
  stats().count("corrections_published");
  const auto deadline = std::chrono::steady_clock::now() + options_.mapper_timeout;
  for (;;) {
    take_all();
    if (auto it = corrections_applied_.find(id);
        it != corrections_applied_.end() && mirror_.map().version >= it->second) {
      corrections_applied_.erase(it);
      // A restarted mapper acknowledges a replayed correction again (docs/local_mapper.md): no conflict.
      keyframe_done_roles_->done(id);
      return true;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline || shutdown_requested()) break;
    if (waitset_->wait(std::min<std::chrono::nanoseconds>(kWaitPeriod, deadline - now)) == runtime::Wake::kShutdown)
      break;
  }
  if (!shutdown_requested()) {
    stats().count("correction_timeouts");
    log().warn("loop correction ", format_id(id), ": the local mapper did not acknowledge it within ",
               options_.mapper_timeout.count(), " ms; going on");
  }
  return false;
}

void LoopCloserNode::acknowledge(KeyframeId id) {
  // Discovery is asynchronous: wait once for a lockstep reader so the first acknowledgement after a
  // (re)start is not lost; later ones never wait.
  if (!reader_wait_done_) {
    reader_wait_done_ = true;
    if (keyframe_done_writer_->matched_readers() == 0) keyframe_done_writer_->wait_for_readers(1, kReaderWait);
  }
  msg::KeyframeDone done{};
  done.keyframe_id = id;
  done.component = runtime::borrow(name());
  done.map_version = mirror_.map().version;
  keyframe_done_writer_->write(done);
}

void LoopCloserNode::load_mapper_map() {
  if (options_.mapper_map_file.empty()) return;
  std::error_code error;
  // The mapper writes a loaded map to its map file (and FILE.run, this run's identity) before it runs,
  // and the pipeline starts the loop closer after it; a file of an earlier run is not this map.
  if (!std::filesystem::exists(options_.mapper_map_file, error) ||
      !runtime::RunJournal::written_by_run(map_run_file_path(options_.mapper_map_file), runtime::supervisor_run_id(),
                                           kMapRunFileFormat)) {
    log().info("no map of this run's local mapper in ", options_.mapper_map_file.string(), " yet: starting empty");
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  MapSnapshot snapshot = load_map_file(options_.mapper_map_file);  // a bad file: one line, exit 1
  if (!snapshot.journal.warning.empty()) log().warn(snapshot.journal.warning);
  const double load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stats().record_ms("map_load", load_ms);
  std::set<MapId> maps;
  for (const auto& [id, keyframe] : snapshot.map.keyframes) maps.insert(keyframe.map_id);
  log().info("took the local mapper's map from ", options_.mapper_map_file.string(), ": ",
             snapshot.map.keyframes.size(), " keyframes, ", snapshot.map.points.size(), " points in ", maps.size(),
             maps.size() == 1 ? " map" : " maps", ", loaded in ", load_ms,
             " ms; its places are loop and merge candidates from the first keyframe on");
  mirror_.load(std::move(snapshot.map));
}

// State file: a run file (runtime/run_journal.hpp) replaced whole after every keyframe, its records
// "last <keyframe>" (one per agent: the last processed keyframe of each creator), "counter <n>", then "loop <loop kf>
// <matched kf>" per loop closed.
void LoopCloserNode::load_state() {
  if (options_.state_file.empty()) return;
  state_file_.emplace(options_.state_file, kStateFileFormat);
  const runtime::RunJournal::Contents contents = state_file_->open_for_run(runtime::supervisor_run_id());
  if (contents.other_file_replaced) {
    log().info("state file ", options_.state_file.string(), " is from an earlier run; starting afresh");
  }
  if (contents.dropped_lines() > 0) {
    // A snapshot missing some of its lines is no state the loop closer was ever in.
    stats().count("state_file_dropped_lines", contents.dropped_lines());
    log().warn(contents.dropped_report(options_.state_file), "; starting afresh");
  }
  if (!contents.same_run || contents.dropped_lines() > 0) {
    save_state();
    return;
  }
  std::map<std::uint8_t, KeyframeId> last;
  std::uint64_t counter = 0;
  std::vector<std::pair<KeyframeId, KeyframeId>> loops;
  for (const std::string& record : contents.records) {
    std::istringstream fields(record);
    std::string key;
    fields >> key;
    if (key == "last") {
      KeyframeId id = kNoId;
      fields >> id;
      if (id != kNoId) last[creator_of(id)] = id;
    } else if (key == "counter") {
      fields >> counter;
    } else if (key == "loop") {
      KeyframeId a = kNoId;
      KeyframeId b = kNoId;
      fields >> a >> b;
      loops.emplace_back(a, b);
    }
  }
  last_processed_ = std::move(last);
  correction_counter_ = std::max(correction_counter_, counter);
  restored_loops_ = std::move(loops);
  std::string processed;
  for (const auto& [creator, id] : last_processed_) processed += (processed.empty() ? "" : ", ") + format_id(id);
  log().info("resuming: keyframes up to ", processed.empty() ? "0" : processed, " processed, ", restored_loops_.size(),
             " loops closed");
}

void LoopCloserNode::save_state() {
  if (!state_file_) return;
  // One "last" record per creator (per agent); a single agent's file reads as before.
  std::vector<std::string> records;
  for (const auto& [creator, id] : last_processed_) records.push_back("last " + std::to_string(id));
  if (records.empty()) records.push_back("last 0");
  records.push_back("counter " + std::to_string(correction_counter_));
  const auto& loops = closing_ ? closing_->loop_edges() : restored_loops_;
  for (const auto& [a, b] : loops) records.push_back("loop " + std::to_string(a) + " " + std::to_string(b));
  state_file_->replace(records);
}

void LoopCloserNode::log_summary() {
  const auto counters = stats().counters();
  const auto count = [&](const char* key) { return counters.count(key) != 0 ? counters.at(key) : 0; };
  log().info("map copy: ", mirror_.map().keyframes.size(), " keyframes, ", mirror_.map().points.size(),
             " points (map version ", mirror_.map().version, ", point ids ", point_ids_digest(mirror_.map()), ")");
  log().info("processed ", count("keyframes"), " keyframes: ", count("candidates"), " loop candidates, ",
             count("loops_accepted"), " loops accepted, ", count("loops_rejected"), " rejected, ",
             count("global_bundle_adjustments"), " global BAs (", count("global_ba_aborted"), " aborted), ",
             count("correction_timeouts"), " corrections unacknowledged");
  if (count("four_dof_corrections") > 0) {
    log().info(count("four_dof_corrections"), " of the loops corrected with the 4-DoF pose graph (inertial run)");
  }
  if (count("bad_gravities") + count("odometry_wait_timeouts") > 0) {
    log().warn("odometry: ", count("bad_gravities"), " gravities refused, ", count("odometry_wait_timeouts"),
               " keyframes gone on without their frame's odometry");
  }
  if (count(runtime::kSecondWriterSamples) + count("bad_keyframes") + count("bad_keyframe_states") +
          count("bad_point_states") >
      0) {
    log().warn("samples refused: ", count(runtime::kSecondWriterSamples), " from second writers (",
               count(runtime::kSecondWriters), " writers, ", count(runtime::kOtherRunWriters), " of another run), ",
               count("bad_keyframes"), " bad keyframes, ", count("bad_keyframe_states"), " bad keyframe states, ",
               count("bad_point_states"), " bad point states");
  }
  for (const runtime::StageSummary& stage : stats().stages()) {
    log().info("stage ", stage.name, " median ", stage.p50_ms, " ms, p90 ", stage.p90_ms, " ms, max ", stage.max_ms,
               " ms (", stage.count, ")");
  }
}

}  // namespace heslam::loop_closer
