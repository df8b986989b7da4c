// Options of heslam-frontend: the process's wiring from its YAML config (config/frontend/*.yaml:
// mapper, lockstep, vocabulary, journal), the vision and tracking tunables from the settings file it
// names (an ORB-SLAM2 settings file, config/camera/*.yaml, read by components/core/tracking/
// settings_file.hpp as the offline harness and the benchmarks read it). Every field is optional; a
// missing one keeps the core library's default (docs/configuration.md, Settings file).
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/map/map.hpp"
#include "components/core/place/vocabulary.hpp"
#include "components/core/tracking/tracker_options.hpp"
#include "components/frontend/inertial_frontend.hpp"
#include "components/frontend/load_shedding.hpp"
#include "runtime/config.hpp"

namespace heslam::frontend {

struct FrontendOptions {
  StereoFeaturePipelineOptions features;  // the settings file's HE.*, ORBextractor.*, Stereo.*, Pipeline.*
  TrackerOptions tracker;                 // its Camera.fps, ThDepth, Tracker.*
  // settings.file / --settings FILE (wins): the ORB-SLAM2 settings file. Empty: the core defaults
  // (those of config/camera/EuRoC.yaml). With a local mapper, Tracker.referenceNearClipWeight
  // defaults to 0 (docs/configuration.md).
  std::filesystem::path settings_file;
  std::vector<std::string> settings_unused_keys;  // keys of it nothing reads (warned at start)
  double settings_camera_fx = 0.0;                // its Camera.fx / Camera.bf, compared with the data's calibration
  double settings_camera_bf = 0.0;
  // vocabulary.file: the ORB vocabulary of the tracker's keyframe database (a lost frame is
  // relocalized anywhere in the map). Empty: the build's default vocabulary; "none": no vocabulary
  // (warned; relocalization against the newest keyframes only). Loaded by from_config: a missing or
  // malformed file ends the process with one line naming it.
  std::string vocabulary_file;
  std::shared_ptr<const Vocabulary> vocabulary;  // null for "none"

  // mapper.enabled: a local mapper owns the map. The frontend then mirrors map/keyframe_states and
  // map/points into its tracker and does not maintain the map itself (TrackerOptions::maintain_map).
  bool mapper_enabled = false;
  // lockstep.wait_for_mapper: before acknowledging a frame that created a keyframe, wait for the
  // mapper's KeyframeDone of that keyframe (deterministic runs with a mapper). Implies mapper_enabled.
  bool wait_for_mapper = false;
  // lockstep.loop_closer / --loop-closer EXECUTABLE: the pipeline's loop closer ("none": none). With
  // one and wait_for_mapper, the frontend also waits for the KeyframeDone of the component named
  // lockstep.loop_closer_name (default "loop_closer"): it acknowledges a keyframe once it has checked
  // it for a loop and the mapper applied any correction.
  std::vector<std::string> loop_closers;
  // lockstep.mapper_timeout_s: how long to wait for that KeyframeDone before giving up (warned,
  // counted) and acknowledging anyway, so a dead mapper cannot hang the run.
  std::chrono::milliseconds mapper_timeout{30000};
  // mapper.map_file / --mapper-map-file FILE: the local mapper's map file. A frontend restarted while
  // the mapper holds a map loads the keyframes (features included, which the state topics do not
  // carry) from it, then relocalizes in that map (ARCHITECTURE.md, Recovery). Only a file of this
  // run counts (FILE.run names the supervisor that wrote it). Empty: a restarted frontend starts a
  // new map.
  std::filesystem::path mapper_map_file;
  // --localize: tracking in a saved map (config/pipelines/euroc_localize.yaml). The mapper's map file
  // must exist at start (the mapper loaded the saved map into it), the first tracked frame is reported
  // ("relocalized in the saved map at frame N"), and a run that never relocalizes fails (exit 1).
  bool localize = false;
  // --session: mapping on a saved map (multi-session, docs/local_mapper.md, Multi-session mapping). As
  // with --localize the mapper's map file must exist at start and the first frames are relocalized in
  // it; a session that is not relocalized within session_new_map_after_s starts a map of its own (the
  // atlas: its id above every loaded one), which the loop closer merges into the saved map when it
  // recognises a place of it. Not with --localize.
  bool session = false;
  // session.new_map_after_s: at the start of a session, how long (frame stamps) the first frames are
  // relocalized in the saved map before a new map starts; after the first pose the atlas's rule
  // (new_map_after_s) holds.
  double session_new_map_after_s = 0.1;
  // --agent N (docs/agents.md): the agent id that goes into every keyframe, point and map id this
  // frontend creates (components/core/map/ids.hpp); 0, a single agent, keeps the ids of before.
  int agent = 0;
  // --mapping on|off: off is localization only (TrackerOptions::create_keyframes = false, ORB-SLAM3's
  // localization mode): with --localize, frames are tracked in the saved map and relocalized in it
  // when lost, and no keyframe or point is created, so the map stays as saved. Needs --localize.
  bool mapping = true;
  // --saved-map FILE: the user's map the mapper loaded (--load-map), named in the messages of a
  // localization run instead of the working copy (mapper_map_file). Empty: mapper_map_file.
  std::filesystem::path saved_map;
  // journal.file / --journal FILE: every finished frame is appended here (OdometryJournal); a
  // restarted frontend of the same run resumes after its last seq and publishes the journaled
  // odometry again. Empty: a restarted frontend tracks every frame it is sent.
  std::filesystem::path journal_file;
  // frames.max_pending: frames that arrive before the calibration are kept (oldest dropped beyond).
  int max_pending_frames = 8;
  // imu.*: inertial tracking (docs/frontend.md, Inertial tracking); --imu auto|none (none wins: off).
  InertialOptions inertial;
  // realtime.*, debug.frame_delay_ms: load shedding of a real-time frontend (load_shedding.hpp).
  LoadSheddingOptions shedding;
  // atlas.new_map_after_s (docs/frontend.md, Atlas): lost and not relocalized in any map for this long
  // (frame stamps), the frontend starts a new map; 0 = never. Sets tracker.new_map_after_ns; never with
  // --localize (a frame stays lost until it is relocalized in the saved map).
  double new_map_after_s = 1.0;

  // Throws std::runtime_error (one line: file, field, expectation) on a bad field.
  // `rest`: the command line's own arguments (--settings FILE, --mapper-map-file FILE, --journal FILE,
  // --loop-closer EXECUTABLE, --localize), which win over the config.
  static FrontendOptions from_config(const runtime::Config& config, const std::vector<std::string>& rest = {});
};

// The failure of a localization run in which no frame was ever tracked in the saved map: names the
// user's map (and the working copy when it is another file).
std::string never_relocalized_message(const FrontendOptions& options, std::uint64_t frames);

}  // namespace heslam::frontend
