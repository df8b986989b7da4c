// Options of the heslam-local-mapper process: the core LocalMapper's tunables plus persistence and
// lockstep. Read from the component config (config/local_mapper/*.yaml) and the command line.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "components/core/mapping/inertial_mapping.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "runtime/config.hpp"

namespace heslam::local_mapper {

struct MapperProcessOptions {
  LocalMapperOptions mapper;
  // map_file / --map-file FILE: the map is saved there after every `save_every_keyframes` keyframes
  // and every correction; a (re)started mapper resumes from it. Empty = no persistence.
  std::filesystem::path map_file;
  // load_map / --load-map FILE: start from this saved map (read once; map_file, when it exists,
  // takes precedence because it is newer: a restart of the same run).
  std::filesystem::path load_map;
  // --load-map "" (an empty value given on purpose, as euroc_localize passes an unset `map`) is an
  // error, never a silent fresh map.
  bool load_map_given_empty = false;
  // save_map / --save-map FILE: when the run ends, the final map is written there as well (the
  // explicit "save" verb; map_file is the run's own working copy). Empty = none.
  std::filesystem::path save_map;
  // --extend-map (multi-session mapping, the session pipelines): with --load-map and no --save-map, the
  // final map (the loaded one and what this run added) replaces the loaded file when the run ends,
  // written to FILE.tmp, fsynced and renamed over it; until then the file is only read, so a run that
  // dies leaves it as it was.
  bool extend_map = false;
  // save_every_keyframes: snapshot cadence. 1 = after every keyframe (a kill -9 then loses nothing;
  // larger values re-process the missing keyframes from DDS on restart, which also loses nothing as
  // long as the frontend still holds them).
  int save_every_keyframes = 1;
  // sync_writes: fsync each snapshot before its rename and each journal record (durable across power
  // loss; slower).
  bool sync_writes = false;
  // map_journal.enabled: a save appends what changed since the previous one to FILE.journal
  // (map_journal.hpp) instead of rewriting the whole map; false: a full snapshot at every save.
  bool map_journal = true;
  // map_journal.compact_ratio: a full snapshot instead of a record once the journal is larger than
  // this x the snapshot (bounds the journal, and the time to reload it, by the snapshot's size).
  double map_journal_compact_ratio = 1.0;
  // map_journal.verify (a test aid, off): after every save, FILE is loaded back (snapshot + journal)
  // and compared with the map in memory; a difference is one error line and exit 1.
  bool map_journal_verify = false;
  // test.kill_after_saved_keyframes (a test aid, 0 = off): the first start of the process (not a
  // restart) kills itself with SIGKILL right after the save of the N-th keyframe it mapped, before
  // that keyframe's states are published: the restart window of docs/local_mapper.md made exact.
  int test_kill_after_saved_keyframes = 0;
  // lockstep.reader_wait_s: before the first KeyframeDone, wait up to this long for the frontend's
  // reader to match. Lockstep acks are transient-local, so one written earlier still arrives; this
  // stays as a cheap guard.
  std::chrono::milliseconds reader_wait{2000};
  // real_time: a local BA stops after the iteration in which a new keyframe is waiting (taken or
  // not yet taken), as ORB-SLAM2's local mapping does; the frontend is not held up by mapping. Off
  // (the default, and what lockstep runs need): every BA runs to completion, so runs are repeatable.
  bool real_time = false;
  // batch_map_writes: the map state writers pack the samples of one publish into few network
  // messages, flushed after the batch's version markers (write_batch.hpp), instead of one datagram
  // per sample.
  bool batch_map_writes = true;
  // --agents N (docs/agents.md): keyframes come from the frontends of agents 0..N-1, several writers of
  // map/keyframes, each held to its agent's ids and maps (AgentKeyframeGuard). 1: one frontend, the
  // topic's single-writer rule (runtime/checked_reader.hpp) as before.
  int agents = 1;
  // imu.* / --imu auto|none: the inertial local BA (docs/local_mapper.md, Inertial local BA). Off by default.
  InertialMappingOptions inertial;

  // Reads the config, then `--map-file FILE` / `--load-map FILE` / `--save-map FILE` / `--imu auto|none` from `rest`
  // (the command line wins). Throws std::runtime_error naming the config file and field, or the bad argument.
  static MapperProcessOptions from_config(const runtime::Config& config, const std::vector<std::string>& rest);
};

}  // namespace heslam::local_mapper
