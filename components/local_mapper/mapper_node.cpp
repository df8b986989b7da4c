// heslam-local-mapper's DDS side (see mapper_node.hpp).
#include "components/local_mapper/mapper_node.hpp"

#include <signal.h>

#include <algorithm>
#include <charconv>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/map/ids.hpp"
#include "components/core/map/point_ids_digest.hpp"
#include "components/local_mapper/write_batch.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/keyframe.hpp"
#include "components/messages/loop_correction.hpp"
#include "components/messages/map_state.hpp"
#include "runtime/atomic_file.hpp"
#include "runtime/heap.hpp"
#include "runtime/run_id.hpp"
#include "runtime/run_journal.hpp"
#include "runtime/run_self.hpp"
#include "runtime/sequence.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::local_mapper {
namespace {

// Keyframes still waiting when the stop comes that are mapped before the final save (a real-time run's
// last ones; more means the mapper was far behind, and the stop must stay within stop_timeout_s).
constexpr std::size_t kKeyframesMappedAtStop = 20;
// Wait granularity of the main loop: shutdown is also signalled through the waitset, this only
// bounds how long a missed wake-up could delay it.
constexpr std::chrono::milliseconds kWaitPeriod{200};
// Samples of a second writer kept in case it takes over (a restarted frontend / loop closer within
// the 2 s lease of the dead one): a frontend waits for each keyframe, a loop closer replays at most
// its correction history (KEEP_LAST(100), docs/topics.md). A keyframe is ~60 KB.
constexpr std::size_t kHeldKeyframes = 64;
constexpr std::size_t kHeldCorrections = 100;

// The per-keyframe stages in pipeline order (status percentiles and the final summary).
// `*_cpu`: CPU time of the mapper's thread in that stage, the figure to compare on a loaded machine.
constexpr const char* kStageOrder[] = {
    "insertion",         "point_culling",         "triangulation",    "fusion",        "local_ba",  "local_ba_cpu",
    "local_ba_inertial", "local_ba_inertial_cpu", "keyframe_culling", "mapping_total", "map_save",  "map_save_journal",
    "map_save_snapshot", "map_save_final",        "publish",          "publish_cpu",   "correction"};

// CPU time of the calling thread, milliseconds.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// FILE.removed: the points the last saved step removed (docs/local_mapper.md, The restart window).
constexpr const char* kRemovedPointsHeader = "heslam-mapper-removed-points 1";

std::filesystem::path removed_points_path(const std::filesystem::path& map_file) {
  std::filesystem::path path = map_file;
  path += ".removed";
  return path;
}

std::uint64_t counter(const std::map<std::string, std::uint64_t>& counters, const char* name) {
  const auto it = counters.find(name);
  return it == counters.end() ? 0 : it->second;
}

// The newest keyframe `creator` made in the map (ids grow per creator: ids.hpp), kNoId when none.
KeyframeId newest_of_creator(const Map& map, std::uint8_t creator) {
  auto after = creator == 0xff ? map.keyframes.end()
                               : map.keyframes.lower_bound(make_id(static_cast<std::uint8_t>(creator + 1), 0));
  if (after == map.keyframes.begin()) return kNoId;
  --after;
  return creator_of(after->first) == creator ? after->first : kNoId;
}

}  // namespace

MapperNode::MapperNode(const runtime::CommonArgs& args) : Component("local_mapper", args) {}

void MapperNode::configure(const runtime::Config& config) {
  options_ = MapperProcessOptions::from_config(config, args().rest);
  waitset_ = std::make_unique<runtime::WaitSet>(participant());
  runtime::CheckedReaderOptions keyframe_options = messages::checked_options<msg::Keyframe>(kHeldKeyframes);
  if (options_.agents > 1) {
    // Several frontends write map/keyframes: each is held to its agent's ids instead (take_keyframes).
    keyframe_options.single_writer = false;
    agent_guard_.emplace(options_.agents);
  }
  keyframe_reader_.emplace(participant(), topics().keyframes(), log(), stats(), nullptr, keyframe_options);
  correction_reader_.emplace(participant(), topics().loop_corrections(), log(), stats(), nullptr,
                             messages::checked_options<msg::LoopCorrection>(kHeldCorrections));
  waitset_->attach(*keyframe_reader_);
  waitset_->attach(*correction_reader_);
  // The map outlives this process: a mapper that exits (or is restarted) must not make the readers
  // delete every keyframe and point (the recorder would lose the refined keyframe poses).
  {
    const BatchedWriterCreation batched(options_.batch_map_writes);  // these two writers only (write_batch.hpp)
    keyframe_state_writer_.emplace(participant(), topics().keyframe_states(),
                                   runtime::Qos(runtime::QosRole::kMapState).keep_instances_on_writer_exit());
    point_state_writer_.emplace(participant(), topics().map_points(),
                                runtime::Qos(runtime::QosRole::kMapState).keep_instances_on_writer_exit());
  }
  mapper_keyframe_writer_.emplace(participant(), topics().mapper_keyframes());
  keyframe_done_writer_.emplace(participant(), topics().keyframe_done());
  if (options_.real_time) {
    // Taken-but-queued keyframes count too: with a backlog, finishing this BA only delays them.
    options_.mapper.bundle_adjustment.stop_requested = [this] {
      return !pending_.empty() || keyframe_reader_->has_unread();
    };
  }
  if (options_.inertial.enabled) configure_inertial();
  if (!options_.map_file.empty()) removed_file_ = removed_points_path(options_.map_file);
  load_initial_map();
  if (!options_.map_file.empty()) {
    MapJournalOptions journal;
    journal.enabled = options_.map_journal;
    journal.compact_ratio = options_.map_journal_compact_ratio;
    journal.sync = options_.sync_writes;
    map_journal_ = std::make_unique<MapJournal>(options_.map_file, journal);
  }
  log().info(
      options_.map_file.empty() ? std::string("no map file (map not persisted)")
                                : "map file " + options_.map_file.string() + ", saved every " +
                                      std::to_string(options_.save_every_keyframes) + " keyframe(s)",
      options_.real_time ? "; real-time: local BA stops when a new keyframe waits" : "; local BA always completes");
}

void MapperNode::load_initial_map() {
  bool resume = false;
  std::vector<std::string> applied_corrections;
  if (!options_.map_file.empty()) {
    run_file_.emplace(map_run_file_path(options_.map_file), kMapRunFileFormat);
    const runtime::RunJournal::Contents contents = run_file_->open_for_run(runtime::supervisor_run_id());
    if (contents.dropped_lines() > 0) {
      stats().count("run_file_dropped_lines", contents.dropped_lines());
      log().warn(contents.dropped_report(run_file_->path()));
    }
    resume = contents.same_run && std::filesystem::exists(options_.map_file);
    if (resume) {
      applied_corrections = contents.records;
    } else {
      // A map file of an earlier run is replaced, not continued: remove it now so a restart of THIS
      // run before our first save starts from scratch too (and re-maps from the DDS keyframes).
      if (std::filesystem::exists(options_.map_file)) {
        log().info("map file ", options_.map_file.string(), " is from an earlier run; starting a new map");
      }
      std::filesystem::remove(options_.map_file);
      std::filesystem::remove(map_journal_path(options_.map_file));
      std::filesystem::remove(removed_file_);
      if (contents.same_run) run_file_->replace({});  // the corrections applied were the removed map's
    }
  }
  if (resume) {
    try {
      loaded_ = load_map_file(options_.map_file);
    } catch (const std::exception& error) {
      // Unusable (e.g. a disk problem): re-map from the keyframes DDS still holds instead of failing
      // again on every restart.
      log().warn(error.what(), "; starting a new map");
      stats().count("unreadable_map_files");
      resume = false;
    }
  }
  if (resume) {
    load_applied_corrections(applied_corrections);
    if (!loaded_->journal.warning.empty()) {
      stats().count("map_journal_dropped_records");
      log().warn(loaded_->journal.warning);
    }
    log().info("resuming from ", options_.map_file.string(), " (snapshot + ", loaded_->journal.records,
               " journal records): ", loaded_->map.keyframes.size(), " keyframes, ", loaded_->map.points.size(),
               " points, map version ", loaded_->map.version);
    // Published at once, not at the first keyframe: when the frontend died too (a power glitch, an
    // OOM kill), no keyframe comes until a restarted frontend has resumed in this map, and it waits
    // for these states to do so. The file is this run's (FILE.run), so there is nothing to confirm.
    // The points the last saved step removed are disposed again: killed after that save and before
    // its states were all published, the readers' mirrors would keep them for good.
    publish_all(loaded_->map, read_removed_points());
  } else if (!options_.load_map.empty()) {
    const auto load_start = std::chrono::steady_clock::now();
    loaded_ = load_map_file(options_.load_map);
    if (!loaded_->journal.warning.empty()) log().warn(loaded_->journal.warning);
    const double load_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - load_start).count();
    stats().record_ms("map_load", load_ms);
    for (const auto& [id, keyframe] : loaded_->map.keyframes) loaded_keyframe_ids_.insert(id);
    log().info("loaded ", options_.load_map.string(), ": ", loaded_->map.keyframes.size(), " keyframes, ",
               loaded_->map.points.size(), " points, map version ", loaded_->map.version, " in ", load_ms, " ms");
    // An explicitly loaded map is published right away (a viewer or a frontend may want it before
    // any keyframe arrives); a resumed one only once the run's keyframes confirm it is this run's.
    publish_all(loaded_->map);
    // ... and it is this run's map from now on: in the map file at once, so a frontend finds its
    // keyframes there (the state topics carry no features) and a restart resumes from it.
    if (!options_.map_file.empty()) {
      save_map_file(options_.map_file, loaded_->map, loaded_->state, options_.sync_writes,
                    loaded_->camera ? &*loaded_->camera : nullptr);
    }
  }
}

void MapperNode::run() {
  while (!shutdown_requested()) {
    if (waitset_->wait(kWaitPeriod) == runtime::Wake::kShutdown) break;
    log().flush_throttled(/*due_only=*/true);
    take_keyframes();
    take_corrections();
    process_pending();
    apply_corrections();
  }
  map_keyframes_left_at_stop();
  if (mapper_ && map_journal_ && (unsaved_keyframes_ > 0 || map_journal_->records() > 0)) {
    // The file left behind is one snapshot, as any reader (an older build too) expects a saved map.
    const auto timer = stats().time("map_save_final");
    last_save_ = map_journal_->compact(mapper_->map(), mapper_->state(), &mapper_->camera(), /*keep_journal=*/false);
    unsaved_keyframes_ = 0;
  }
  if (!removed_file_.empty()) std::filesystem::remove(removed_file_);  // the run is over: no restart reads it
  log().flush_throttled();
  log_summary();
  if (!options_.save_map.empty()) save_map_to(options_.save_map);
}

void MapperNode::save_map_to(const std::filesystem::path& path) {
  std::error_code error;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), error);
  // The user's saved map extended in place (--extend-map) is replaced atomically (FILE.tmp renamed over
  // it) and durably: the only copy of the earlier sessions' map must survive a power loss too.
  const bool replaces_loaded =
      !options_.load_map.empty() && std::filesystem::equivalent(path, options_.load_map, error);
  if (mapper_) {
    mapper_->save(path, options_.sync_writes || replaces_loaded);
    log().info("saved the map to ", path.string(), ": ", mapper_->map().keyframes.size(), " keyframes, ",
               mapper_->map().points.size(), " points");
    if (!options_.load_map.empty()) log_session_map(path);
  } else if (loaded_) {
    // Loaded, and no keyframe arrived to start mapping: the map is the loaded one.
    save_map_file(path, loaded_->map, loaded_->state, options_.sync_writes || replaces_loaded,
                  loaded_->camera ? &*loaded_->camera : nullptr);
    log().info("saved the map to ", path.string(), ": ", loaded_->map.keyframes.size(), " keyframes (as loaded)");
  } else {
    throw std::runtime_error("--save-map " + path.string() + ": no map to save (not one keyframe arrived)");
  }
}

void MapperNode::take_keyframes() {
  for (auto& received : keyframe_reader_->take()) {
    if (!received.info.valid_data) continue;  // a frontend that left: its keyframes stay in the map
    const msg::Keyframe& message = *received.sample;
    if (agent_guard_ && !admit_agent_keyframe(message, received.info.publication_handle)) continue;
    try {
      if (auto problem = messages::check(message))
        throw std::runtime_error("topic '" + keyframe_reader_->name() + "': " + *problem);
      PendingKeyframe keyframe{messages::to_keyframe(message), messages::to_camera(message.camera)};
      if (!(keyframe.camera.fx_px > 0.0) || !(keyframe.camera.baseline_m > 0.0)) {
        throw std::runtime_error("keyframe " + format_id(message.id) + ": camera fx " +
                                 std::to_string(keyframe.camera.fx_px) + " px, baseline " +
                                 std::to_string(keyframe.camera.baseline_m) + " m (expected both > 0)");
      }
      pending_.insert_or_assign(message.id, std::move(keyframe));
    } catch (const std::exception& error) {
      stats().count("bad_keyframes");
      log().warn_throttled("bad_keyframes", error.what());
      acknowledge(message.id);  // a lockstep frontend must not wait for a keyframe we cannot use
    }
  }
}

bool MapperNode::admit_agent_keyframe(const msg::Keyframe& message, dds_instance_handle_t writer) {
  if (!runtime::writer_of_this_run(keyframe_reader_->handle(), writer)) {
    stats().count(runtime::kSecondWriterSamples);
    return false;  // another run's frontend on the domain: neither mapped nor acknowledged
  }
  // A restarted mapper holds its resumed map in loaded_ until the first keyframe to map brings the camera;
  // the keyframes DDS delivers again before that (every agent's, in maps merged long ago) are checked there.
  const Map* map = mapper_ ? &mapper_->map() : loaded_ ? &loaded_->map : nullptr;
  const auto map_exists = [map](MapId map_id) {
    if (map == nullptr) return false;
    for (const auto& [id, keyframe] : map->keyframes) {
      if (keyframe.map_id == map_id) return true;
    }
    return false;
  };
  const std::optional<std::string> problem = agent_guard_->check(writer, message.id, message.map_id, map_exists);
  if (!problem) return true;
  stats().count("refused_agent_keyframes");
  log().warn_throttled("refused_agent_keyframes", "topic '", keyframe_reader_->name(), "': ", *problem,
                       "; refused (counted as refused_agent_keyframes)");
  acknowledge(message.id);  // its lockstep frontend must not wait for a keyframe we will not map
  return false;
}

void MapperNode::take_corrections() {
  for (auto& received : correction_reader_->take()) {
    if (!received.info.valid_data) continue;
    try {
      if (auto problem = messages::check(*received.sample)) {
        throw std::runtime_error("topic '" + correction_reader_->name() + "': " + *problem);
      }
      LoopCorrection correction = messages::to_loop_correction(*received.sample);
      if (applied_corrections_.count(correction.id) != 0) {
        // Replayed to us after a restart: applied already, but its loop closer may still wait for the
        // acknowledgement this process died before sending.
        acknowledge(correction.loop_kf, correction.id);
        continue;
      }
      pending_corrections_.insert_or_assign(correction.id, std::move(correction));
    } catch (const std::exception& error) {
      stats().count("bad_corrections");
      log().warn_throttled("bad_corrections", error.what());
    }
  }
}

void MapperNode::process_pending() {
  while (!pending_.empty() && !shutdown_requested()) {
    PendingKeyframe keyframe = std::move(pending_.begin()->second);
    pending_.erase(pending_.begin());
    process_keyframe(std::move(keyframe));
  }
}

void MapperNode::map_keyframes_left_at_stop() {
  // In real time the stop (SIGTERM) comes once the frontend has written its result, which it does after
  // its writers' data was acknowledged: its last keyframes are here, unread or pending. They are mapped
  // (and saved below) rather than lost with the run's end; at most kKeyframesMappedAtStop, each BA bounded
  // as any other, so the stop stays within the supervisor's stop_timeout_s.
  take_keyframes();
  take_corrections();
  std::size_t mapped = 0;
  while (!pending_.empty() && mapped < kKeyframesMappedAtStop) {
    PendingKeyframe keyframe = std::move(pending_.begin()->second);
    pending_.erase(pending_.begin());
    process_keyframe(std::move(keyframe));
    ++mapped;
  }
  apply_corrections();
  if (mapped > 0) log().info("mapped ", mapped, " keyframe(s) that arrived before the stop");
  if (!pending_.empty()) {
    stats().count("keyframes_unmapped_at_stop", pending_.size());
    log().warn(pending_.size(), " keyframe(s) still waiting at the stop were not mapped (at most ",
               kKeyframesMappedAtStop, " are mapped after SIGTERM); counted as keyframes_unmapped_at_stop");
  }
}

void MapperNode::start_mapper(const PendingKeyframe& first) {
  if (loaded_ && loaded_->camera && !same_map_camera(*loaded_->camera, first.camera)) {
    // Keyframes of two cameras in one map would be matched and adjusted with the wrong intrinsics.
    throw std::runtime_error("map " + (options_.load_map.empty() ? options_.map_file : options_.load_map).string() +
                             ": made with another camera (" + describe_map_camera(*loaded_->camera) +
                             ") than this run's keyframes (" + describe_map_camera(first.camera) + ")");
  }
  if (loaded_) {
    mapper_ = std::make_unique<LocalMapper>(first.camera, options_.mapper, std::move(*loaded_));
    loaded_.reset();
  } else {
    mapper_ = std::make_unique<LocalMapper>(first.camera, options_.mapper);
  }
  if (inertial_) {
    mapper_->set_bundle_adjustment(
        [this](Map& map, KeyframeId id, const PinholeStereo& camera, const LocalBundleAdjustmentOptions& ba_options,
               MapChanges& changes) { return inertial_->bundle_adjust(map, id, camera, ba_options, changes); });
  }
  log().info("camera fx ", first.camera.fx_px, " px, baseline ", first.camera.baseline_m, " m; ",
             mapper_->map().keyframes.size(), " keyframes in the map");
  for (const auto& [id, keyframe] : mapper_->map().keyframes) publish_keyframe(keyframe);
}

void MapperNode::publish_keyframe(const Keyframe& keyframe) {
  const messages::KeyframeMessage message(keyframe, /*frame_seq=*/0, /*new_points=*/{}, mapper_->camera(), kNoId,
                                          mapper_->map().version);
  mapper_keyframe_writer_->write(message.get());
}

void MapperNode::process_keyframe(PendingKeyframe keyframe) {
  if (!mapper_) start_mapper(keyframe);
  const KeyframeId id = keyframe.decoded.keyframe.id;
  const Map& map = mapper_->map();
  const KeyframeId newest = newest_of_creator(map, creator_of(id));
  if (map.keyframe(id) == nullptr && newest != kNoId && id < newest) {
    // Keyframe ids only grow within a run (a restarted frontend continues past the map's), so this
    // one is not of this map: mapping it would mix two maps. Per creator: each agent counts its own.
    stats().count("foreign_keyframes");
    log().warn_throttled("foreign_keyframes", "keyframe ", format_id(id),
                         ": not in the map and older than its creator's newest keyframe ", format_id(newest),
                         "; ignored");
    acknowledge(id);
    return;
  }
  if (const Keyframe* known = map.keyframe(id); known != nullptr) {
    if (known->stamp_ns != keyframe.decoded.keyframe.stamp_ns) {
      stats().count("duplicate_keyframe_ids");
      log().warn_throttled("duplicate_keyframe_ids", "keyframe ", format_id(id), ": id already in the map with stamp ",
                           known->stamp_ns, " ns, received with ", keyframe.decoded.keyframe.stamp_ns, " ns; ignored");
      acknowledge(id);
    } else {
      stats().count("keyframes_already_mapped");
      // After a restart the frontend may be waiting for the last keyframe we mapped before dying.
      if (id == mapper_->state().last_keyframe) acknowledge(id);
    }
    return;
  }
  if (inertial_) wait_for_imu(keyframe.decoded.keyframe.stamp_ns, id);
  MapChanges changes;
  try {
    const TrackedAgainst tracked{keyframe.decoded.reference_kf, keyframe.decoded.tracked_map_version};
    changes = mapper_->process_keyframe(std::move(keyframe.decoded.keyframe), std::move(keyframe.decoded.new_points),
                                        tracked);
  } catch (const std::invalid_argument& error) {
    stats().count("bad_keyframes");
    log().warn_throttled("bad_keyframes", error.what());
    acknowledge(id);
    return;
  }
  record(changes);
  if (inertial_) report_inertial(changes);
  unsaved_changes_.merge(changes);
  if (++unsaved_keyframes_ >= options_.save_every_keyframes) save();
  ++keyframes_mapped_here_;
  kill_after_save_for_test(id, changes);
  if (const Keyframe* inserted = mapper_->map().keyframe(id)) publish_keyframe(*inserted);
  publish(changes);
  acknowledge(id);
  if (changes.counts.late_keyframes_moved > 0) {
    log().info("keyframe ", format_id(id), " was tracked at map version ", keyframe.decoded.tracked_map_version,
               ", before a correction applied since: moved with its reference keyframe ",
               format_id(keyframe.decoded.reference_kf));
  }
  log().debug("keyframe ", format_id(id), ": ", changes.timings.total_ms, " ms, ", changes.counts.triangulated_points,
              " new points, ", changes.counts.culled_points, " culled points, ", changes.counts.culled_keyframes,
              " culled keyframes, ", changes.changed_points.size(), " points changed; local BA ",
              changes.counts.bundle_adjustment_free_keyframes, " free + ",
              changes.counts.bundle_adjustment_fixed_keyframes, " fixed keyframes, ",
              changes.counts.bundle_adjustment_points, " points, ", changes.counts.bundle_adjustment_observations,
              " observations, ", changes.timings.bundle_adjustment_cpu_ms, " ms CPU");
}

void MapperNode::apply_corrections() {
  if (!mapper_) return;  // corrections wait for the map (and its camera) to exist
  while (!pending_corrections_.empty()) {
    const LoopCorrection correction = std::move(pending_corrections_.begin()->second);
    pending_corrections_.erase(pending_corrections_.begin());
    std::map<KeyframeId, Pose3> old_T_wc;
    if (inertial_) {
      for (const auto& [id, state] : inertial_->states()) {
        if (const Keyframe* keyframe = mapper_->map().keyframe(id)) old_T_wc.emplace(id, keyframe->T_wc);
      }
    }
    const MapChanges changes = mapper_->apply_correction(correction);
    if (inertial_) inertial_->moved(old_T_wc, mapper_->map());
    stats().count("corrections");
    stats().record_ms("correction", changes.timings.total_ms);
    unsaved_changes_.merge(changes);
    save();
    remember_applied_correction(correction.id);
    publish(changes, correction.id);
    acknowledge(correction.loop_kf, correction.id);
    log().info("loop correction ", format_id(correction.id), " (",
               correction.matched_kf == kNoId
                   ? "global BA after the loop at keyframe " + format_id(correction.loop_kf)
                   : "keyframe " + format_id(correction.loop_kf) + " -> " + format_id(correction.matched_kf),
               "): ", changes.changed_keyframes.size(), " keyframes and ", changes.changed_points.size(),
               " points moved, ", changes.removed_points.size(), " points merged");
  }
}

void MapperNode::record(const MapChanges& changes) {
  const LocalMapperTimings& t = changes.timings;
  stats().count("keyframes");
  stats().record_ms("insertion", t.insertion_ms);
  stats().record_ms("point_culling", t.point_culling_ms);
  stats().record_ms("triangulation", t.triangulation_ms);
  stats().record_ms("fusion", t.fusion_ms);
  stats().record_ms("local_ba", t.bundle_adjustment_ms);
  stats().record_ms("local_ba_cpu", t.bundle_adjustment_cpu_ms);
  stats().record_ms("keyframe_culling", t.keyframe_culling_ms);
  stats().record_ms("mapping_total", t.total_ms);
  const LocalMapperCounts& c = changes.counts;
  stats().count("triangulated_points", static_cast<std::uint64_t>(c.triangulated_points));
  stats().count("fused_points", static_cast<std::uint64_t>(c.fused_points));
  stats().count("culled_points", static_cast<std::uint64_t>(c.culled_points));
  stats().count("culled_keyframes", static_cast<std::uint64_t>(c.culled_keyframes));
  stats().count("ba_outliers", static_cast<std::uint64_t>(c.bundle_adjustment_outliers));
  if (c.bundle_adjustment_aborted) stats().count("ba_stopped_early");
  stats().count("late_keyframes_moved", static_cast<std::uint64_t>(c.late_keyframes_moved));
  stats().count("rejected_observations", static_cast<std::uint64_t>(c.rejected_observations));
  // The map's size (keyframes not culled, points) as two monotonic counters each, X_added - X_removed:
  // a status reader (tools/bench/long_run.sh) follows the map's growth on long runs.
  std::uint64_t keyframes = 0;
  for (const auto& [id, keyframe] : mapper_->map().keyframes) keyframes += keyframe.culled ? 0 : 1;
  report_size("map_keyframes", keyframes, reported_keyframes_);
  report_size("map_points", mapper_->map().points.size(), reported_points_);
}

void MapperNode::report_size(const std::string& name, std::uint64_t now, std::uint64_t& reported) {
  if (now > reported) stats().count(name + "_added", now - reported);
  if (now < reported) stats().count(name + "_removed", reported - now);
  reported = now;
}

void MapperNode::save() {
  unsaved_keyframes_ = 0;
  if (!map_journal_ || !mapper_) return;
  const auto start = std::chrono::steady_clock::now();
  write_removed_points(unsaved_changes_.removed_points);
  last_save_ = map_journal_->save(mapper_->map(), mapper_->state(), &mapper_->camera(), unsaved_changes_);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  unsaved_changes_ = MapChanges{};
  stats().record_ms("map_save", ms);
  stats().record_ms(last_save_.snapshot ? "map_save_snapshot" : "map_save_journal", ms);
  stats().count("map_saves");
  stats().count(last_save_.snapshot ? "map_snapshots" : "map_journal_records");
  stats().count(last_save_.snapshot ? "map_snapshot_bytes" : "map_journal_bytes", last_save_.bytes);
  // A snapshot's buffer (10 MB at 100 keyframes) stays in the heap once freed (glibc raises its mmap
  // threshold to the largest block freed): back to the system, or the RSS keeps it (issue 41).
  if (last_save_.snapshot) {
    const runtime::HeapRelease release = runtime::release_free_heap(&stats());
    log().debug("heap after the snapshot: ", release.released_bytes() / 1024, " KiB returned to the system in ",
                release.elapsed_ms, " ms, RSS ", release.rss_after_bytes / (1024 * 1024), " MiB");
  }
  if (options_.map_journal_verify) verify_map_file();
}

void MapperNode::verify_map_file() {
  const MapSnapshot loaded = load_map_file(options_.map_file);
  if (const auto difference = first_map_difference(loaded.map, loaded.state, mapper_->map(), mapper_->state())) {
    throw std::runtime_error("map_journal.verify: " + options_.map_file.string() + " (snapshot + " +
                             std::to_string(loaded.journal.records) +
                             " journal records) differs from the map: " + *difference);
  }
  stats().count("map_journal_verified");
}

void MapperNode::publish(const MapChanges& changes, std::uint64_t correction_id) {
  const auto timer = stats().time("publish");
  const double cpu_start_ms = thread_cpu_ms();
  const Map& map = mapper_->map();
  for (const KeyframeId id : changes.changed_keyframes) {
    if (const Keyframe* keyframe = map.keyframe(id); keyframe != nullptr) {
      keyframe_state_writer_->write(messages::to_state_message(*keyframe, map.version, covisible_buffer_));
    }
  }
  for (const PointId id : changes.changed_points) {
    if (const MapPoint* point = map.point(id); point != nullptr) {
      point_state_writer_->write(messages::to_state_message(*point, map.version, observation_buffer_));
    }
  }
  for (const auto& [id, into] : changes.removed_points) {
    const msg::MapPointState last = messages::merged_state_message(id, into, map.version);
    if (into != kNoId) point_state_writer_->write(last);  // readers redirect observations to `into`
    point_state_writer_->dispose(last);
    stats().count("disposed_points");
  }
  write_version_markers(map.version, correction_id);
  stats().record_ms("publish_cpu", thread_cpu_ms() - cpu_start_ms);
}

void MapperNode::write_version_markers(std::uint64_t map_version, std::uint64_t correction_id) {
  keyframe_state_writer_->write(messages::keyframe_version_marker(map_version, correction_id));
  point_state_writer_->write(messages::point_version_marker(map_version));
  // The markers end every batch of states: what is still packed leaves now.
  flush_writes({keyframe_state_writer_->handle(), point_state_writer_->handle()});
}

void MapperNode::publish_all(const Map& map, const std::map<PointId, PointId>& removed) {
  const auto timer = stats().time("publish");
  for (const auto& [id, keyframe] : map.keyframes) {
    keyframe_state_writer_->write(messages::to_state_message(keyframe, map.version, covisible_buffer_));
  }
  for (const auto& [id, point] : map.points) {
    point_state_writer_->write(messages::to_state_message(point, map.version, observation_buffer_));
  }
  std::size_t disposed = 0;
  for (const auto& [id, into] : removed) {
    // Still in the map: the kill came before the save, the step is mapped again and removes it then.
    if (map.point(id) != nullptr) continue;
    const msg::MapPointState last = messages::merged_state_message(id, into, map.version);
    if (into != kNoId) point_state_writer_->write(last);
    point_state_writer_->dispose(last);
    ++disposed;
  }
  write_version_markers(map.version);
  log().info("published the state of ", map.keyframes.size(), " keyframes and ", map.points.size(), " points");
  if (disposed > 0) {
    stats().count("redisposed_points", disposed);
    log().info("disposed again ", disposed, " points the last saved step removed (", removed_file_.string(),
               "): its publication may not have finished before this restart");
  }
}

void MapperNode::write_removed_points(const std::map<PointId, PointId>& removed) {
  if (removed_file_.empty() || (removed.empty() && !removed_file_holds_ids_)) return;
  std::ostringstream text;
  text << kRemovedPointsHeader << "\n";
  for (const auto& [id, into] : removed) text << id << " " << into << "\n";
  runtime::replace_file_contents(removed_file_, text.str(), options_.sync_writes);
  removed_file_holds_ids_ = !removed.empty();
}

std::map<PointId, PointId> MapperNode::read_removed_points() {
  std::map<PointId, PointId> removed;
  std::ifstream in(removed_file_);
  if (!in) return removed;  // none yet: no save removed a point
  std::string line;
  if (!std::getline(in, line) || line != kRemovedPointsHeader) {
    log().warn(removed_file_.string(), ": not a removed-points file (first line '", line, "', expected '",
               kRemovedPointsHeader, "'); nothing disposed again");
    return removed;
  }
  PointId id = kNoId;
  PointId into = kNoId;
  while (in >> id >> into) removed.emplace(id, into);
  removed_file_holds_ids_ = !removed.empty();
  return removed;
}

void MapperNode::kill_after_save_for_test(KeyframeId id, const MapChanges& changes) {
  if (options_.test_kill_after_saved_keyframes != keyframes_mapped_here_ || runtime::restart_number() != 0) return;
  log().warn("test.kill_after_saved_keyframes: SIGKILL after the save of keyframe ", format_id(id), ", before its ",
             changes.changed_keyframes.size(), " keyframe states, ", changes.changed_points.size(),
             " point states and ", changes.removed_points.size(), " disposals are published");
  log().flush_throttled();
  ::raise(SIGKILL);
}

void MapperNode::acknowledge(KeyframeId id, std::uint64_t correction_id) {
  // Discovery is asynchronous: wait once for the lockstep reader (the frontend) so the first
  // acknowledgement after a (re)start is not lost; later ones never wait.
  if (!reader_wait_done_) {
    reader_wait_done_ = true;
    if (keyframe_done_writer_->matched_readers() == 0) {
      keyframe_done_writer_->wait_for_readers(1, options_.reader_wait);
    }
  }
  msg::KeyframeDone done{};
  done.keyframe_id = id;
  done.component = runtime::borrow(name());
  done.map_version = mapper_ ? mapper_->map().version : 0;
  done.correction_id = correction_id;
  keyframe_done_writer_->write(done);
}

void MapperNode::configure_inertial() {
  imu_input_.emplace(participant(), topics(), log(), stats(), messages::ImuInput::Camera::kNeeded);
  imu_waitset_ = std::make_unique<runtime::WaitSet>(participant());
  imu_input_->attach(*imu_waitset_);
  inertial_ = std::make_unique<InertialMapping>(options_.inertial, imu_input_->readings_topic());
  inertial_->set_log([this](const std::string& line) { log().warn(line); },
                     [this](const std::string& line) { log().info(line); });
  imu_input_->feed(inertial_->buffer());
  const InertialMappingOptions& o = options_.inertial;
  log().info("inertial local BA: ", imu_input_->readings_topic(), ", ", imu_input_->calibration_topic(), " and ",
             imu_input_->camera_topic(), ", window ", o.window_keyframes, " keyframes, initialization after ",
             o.init_min_keyframes, " keyframes over ", o.init_min_duration_s, " s",
             options_.real_time
                 ? "; real time (never waits for the IMU)"
                 : "; each keyframe waits for the IMU to cover it, at most " + std::to_string(o.wait_s) + " s");
  for (const char* name :
       {"imu_readings", "imu_bad_readings", "imu_ba_inertial", "imu_ba_visual_fallbacks", "imu_ba_failed_solves",
        "imu_ba_factors", "imu_init_attempts", "imu_initialized", "imu_refinements", "imu_off"}) {
    stats().count(name, 0);
  }
}

void MapperNode::take_imu() {
  imu_input_->take();
  if (!inertial_->has_camera() && imu_input_->T_B_rect()) inertial_->set_camera(*imu_input_->T_B_rect());
  if (!inertial_->has_calibration() && imu_input_->calibration()) {
    inertial_->set_imu_calibration(*imu_input_->calibration());
  }
}

void MapperNode::wait_for_imu(std::int64_t stamp_ns, KeyframeId id) {
  take_imu();
  if (inertial_->off() || options_.real_time) return;
  const auto covered = [&] {
    return inertial_->has_calibration() && inertial_->has_camera() &&
           inertial_->buffer().covered_until_ns() >= inertial_->imu_stamp(stamp_ns);
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                               std::chrono::duration<double>(options_.inertial.wait_s));
  while (!covered()) {
    std::string missing = !inertial_->has_camera()        ? "no stereo calibration on '" + imu_input_->camera_topic()
                          : !inertial_->has_calibration() ? "no IMU calibration on '" + imu_input_->calibration_topic()
                                                          : "no IMU readings on '" + imu_input_->readings_topic();
    if (imu_input_->ended()) {
      inertial_->turn_off("the IMU stream ended (end_of_stream) before keyframe " + format_id(id));
      stats().count("imu_off");
      return;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline || shutdown_requested()) {
      inertial_->turn_off(missing + "' up to keyframe " + format_id(id) + " (" + std::to_string(stamp_ns) +
                          " ns) within imu.wait_s " + std::to_string(options_.inertial.wait_s) + " s");
      stats().count("imu_off");
      return;
    }
    imu_waitset_->wait(std::min<std::chrono::nanoseconds>(kWaitPeriod, deadline - now));
    take_imu();
  }
}

void MapperNode::report_inertial(const MapChanges& changes) {
  if (changes.counts.inertial_bundle_adjustment) {
    stats().record_ms("local_ba_inertial", changes.timings.bundle_adjustment_ms);
    stats().record_ms("local_ba_inertial_cpu", changes.timings.bundle_adjustment_cpu_ms);
  }
  const InertialMappingCounts& c = inertial_->counts();
  const ImuBufferCounts& buffer = inertial_->buffer().counts();
  const std::map<std::string, std::uint64_t> now = {
      {"imu_readings", buffer.accepted},         {"imu_bad_readings", buffer.skipped()},
      {"imu_ba_inertial", c.inertial_bas},       {"imu_ba_visual_fallbacks", c.visual_fallbacks},
      {"imu_ba_failed_solves", c.failed_solves}, {"imu_ba_factors", c.imu_factors},
      {"imu_init_attempts", c.init_attempts},    {"imu_initialized", c.initialized},
      {"imu_refinements", c.refinements},
  };
  for (const auto& [name, value] : now) {
    std::uint64_t& reported = imu_counters_reported_[name];
    if (value > reported) stats().count(name, value - reported);
    reported = std::max(reported, value);
  }
}

void MapperNode::load_applied_corrections(const std::vector<std::string>& records) {
  for (const std::string& record : records) {
    std::uint64_t id = 0;
    const auto [end, error] = std::from_chars(record.data(), record.data() + record.size(), id);
    if (error == std::errc() && end == record.data() + record.size()) {
      applied_corrections_.insert(id);
    } else {
      log().warn(run_file_->path().string(), ": '", record, "' is no correction id; skipped");
    }
  }
}

void MapperNode::remember_applied_correction(std::uint64_t id) {
  applied_corrections_.insert(id);
  // Appended after the map was saved: a kill between the two re-applies the correction once, which
  // moves keyframes to the poses it lists again (the same poses) and repeats no merge (merged points
  // are gone).
  if (run_file_) run_file_->append(std::to_string(id));
}

void MapperNode::log_summary() {
  const auto counters = stats().counters();
  std::ostringstream totals;
  totals << "mapped " << counter(counters, "keyframes") << " keyframes ("
         << counter(counters, "keyframes_already_mapped") << " already in the map file, "
         << counter(counters, "bad_keyframes") << " bad), " << counter(counters, "triangulated_points")
         << " points triangulated, " << counter(counters, "culled_points") << " culled, "
         << counter(counters, "culled_keyframes") << " keyframes culled, " << counter(counters, "corrections")
         << " corrections (" << counter(counters, "late_keyframes_moved")
         << " keyframes tracked before one moved into it)";
  if (options_.real_time) totals << "; " << counter(counters, "ba_stopped_early") << " local BAs stopped early";
  if (inertial_) {
    totals << "; inertial local BA: " << counter(counters, "imu_ba_inertial") << " keyframes ("
           << counter(counters, "imu_ba_visual_fallbacks") << " visual fallbacks, "
           << counter(counters, "imu_ba_failed_solves") << " failed solves), IMU "
           << (inertial_->off()           ? "off"
               : inertial_->initialized() ? "initialized"
                                          : "not initialized");
  }
  log().info(totals.str());
  if (counter(counters, runtime::kSecondWriterSamples) > 0 || counter(counters, "bad_corrections") > 0) {
    log().warn("samples refused: ", counter(counters, runtime::kSecondWriterSamples), " from second writers (",
               counter(counters, runtime::kSecondWriters), " writers, ", counter(counters, runtime::kOtherRunWriters),
               " of another run), ", counter(counters, "bad_corrections"), " bad corrections");
  }
  if (mapper_) {
    log().info("map: ", mapper_->map().keyframes.size(), " keyframes, ", mapper_->map().points.size(),
               " points, version ", mapper_->map().version, ", point ids ", point_ids_digest(mapper_->map()));
  }
  const std::vector<runtime::StageSummary> stages = stats().stages();
  for (const char* name : kStageOrder) {
    for (const runtime::StageSummary& stage : stages) {
      if (stage.name != name) continue;
      std::ostringstream line;
      line << std::fixed << std::setprecision(2) << "stage " << std::left << std::setw(16) << stage.name << " median "
           << std::right << std::setw(7) << stage.p50_ms << " ms  p90 " << std::setw(7) << stage.p90_ms << " ms  max "
           << std::setw(7) << stage.max_ms << " ms  (" << stage.count << " keyframes)";
      log().info(line.str());
    }
  }
  if (last_save_.bytes > 0) {
    const std::uint64_t records = counter(counters, "map_journal_records");
    const std::uint64_t snapshots = counter(counters, "map_snapshots");
    log().info("map file ", options_.map_file.string(), ": ", records, " journal records (",
               records > 0 ? counter(counters, "map_journal_bytes") / records : 0, " bytes each on average) and ",
               snapshots, " snapshots (", snapshots > 0 ? counter(counters, "map_snapshot_bytes") / snapshots : 0,
               " bytes each on average) saved; last save ", last_save_.snapshot ? "a snapshot" : "a journal record",
               " of ", last_save_.bytes, " bytes (serialize ", last_save_.serialize_ms, " ms, write ",
               last_save_.write_ms, " ms); snapshot ", last_save_.snapshot_bytes, " bytes, journal ",
               last_save_.journal_bytes, " bytes");
  }
}

// Multi-session mapping (docs/local_mapper.md): what the saved map holds now, of the loaded one and of
// this run, and in how many maps (a session that was never merged into the saved map stays a map of its own).
void MapperNode::log_session_map(const std::filesystem::path& path) {
  std::size_t loaded = 0;
  std::size_t added = 0;
  std::set<MapId> maps;
  for (const auto& [id, keyframe] : mapper_->map().keyframes) {
    (loaded_keyframe_ids_.count(id) != 0 ? loaded : added) += 1;
    if (!keyframe.culled) maps.insert(keyframe.map_id);
  }
  log().info("session map ", path.string(), ": ", loaded, " keyframes of the loaded map ", options_.load_map.string(),
             " and ", added, " of this run, in ", maps.size(),
             maps.size() == 1 ? " map" : " maps (not merged: a session map stays apart until it is)");
}

}  // namespace heslam::local_mapper
