// Versioned binary snapshot of the mapper's map and bookkeeping (the mapper's persistence and the
// map save / load feature).
//
// Layout (little-endian): "HESLAMAP", u32 format version, u32 reserved, u64 payload bytes, payload,
// u64 FNV-1a checksum of the payload. A snapshot replaces <path> whole (runtime/atomic_file.hpp:
// "<path>.tmp", renamed over it), so a process killed mid-write leaves the previous snapshot intact.
//
// The map a file holds is its snapshot plus, when there is one, the journal beside it ("<path>.journal",
// map_journal.hpp): the local mapper appends what each keyframe changed there and rewrites the snapshot
// only now and then. load_map_file reads both, so every reader sees the mapper's latest saved map.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/mapper_state.hpp"

namespace heslam {

// 2: the mapper's correction motions (correction_history.hpp) after the points. Version 1 files
// are still read (no correction remembered).
// 3: the map ids of keyframes and points not in the first map (the atlas), after the correction
// motions. Older files read as one map, the first.
// 4: the rectified stereo camera the map was made with (a flag, then fx, fy, cx, cy, baseline, width,
// height), after the map ids: a saved map loaded with another camera is refused (multi-session mapping).
// Older files have none (not checked).
inline constexpr std::uint32_t kMapFileFormatVersion = 4;
inline constexpr std::uint32_t kOldestReadableMapFileFormatVersion = 1;

// What load_map_file took from the journal beside the snapshot (map_journal.hpp).
struct MapJournalReplay {
  std::uint64_t records = 0;        // records applied
  std::uint64_t dropped_bytes = 0;  // an incomplete or damaged tail left out (a writer killed mid-record)
  bool stale = false;               // a journal of another snapshot (ignored: the snapshot is newer)
  std::string warning;              // one line naming the journal and what was dropped; empty when nothing was
};

struct MapSnapshot {
  Map map;
  MapperState state;
  // The rectified camera of its keyframes; unset in files before format 4 and in maps saved without one.
  std::optional<PinholeStereo> camera;
  MapJournalReplay journal;
};

// Whether `a` and `b` are the same rectified camera (intrinsics, baseline, image size), to a relative
// 1e-6: a map's camera against a run's calibration.
bool same_map_camera(const PinholeStereo& a, const PinholeStereo& b);
// "fx F px, baseline B m, WxH": a camera in messages.
std::string describe_map_camera(const PinholeStereo& camera);

struct MapFileWriteStats {
  std::uint64_t bytes = 0;
  double serialize_ms = 0.0;
  double write_ms = 0.0;       // write + (optional) fsync + rename
  std::uint64_t checksum = 0;  // of the snapshot's payload (a journal names its snapshot by it)
};

// "<map_file>.journal": the records appended since the snapshot (map_journal.hpp).
std::filesystem::path map_journal_path(const std::filesystem::path& map_file);

// The run file a local mapper keeps beside its map file (runtime/run_journal.hpp): FILE.run, naming
// the run that wrote FILE, then the ids of the loop corrections applied to it, one per record. A
// restarted frontend reads its first line to know whether FILE is this run's.
inline constexpr const char* kMapRunFileFormat = "heslam-mapper-run 2";
std::filesystem::path map_run_file_path(const std::filesystem::path& map_file);

// The snapshot's payload (no header, no checksum): two maps (with their mapper state and camera) are the
// same map exactly when these bytes are equal.
std::vector<std::uint8_t> serialize_map_payload(const Map& map, const MapperState& state, const PinholeStereo* camera);

// A full snapshot; a journal beside `path` is removed (the snapshot holds everything).
// Throws std::runtime_error ("map file <path>: <what>") when the file cannot be written.
// `sync` forces the data to disk before the rename (durable across power loss, slower).
// `camera`: the rectified camera of the map's keyframes, stored since format 4 (null: none).
MapFileWriteStats save_map_file(const std::filesystem::path& path, const Map& map, const MapperState& state,
                                bool sync = false, const PinholeStereo* camera = nullptr);

// The snapshot and its journal's complete records (MapSnapshot::journal says what was left out).
// Throws std::runtime_error with one line naming the file and what is wrong (missing, bad magic,
// unsupported version, truncated at which record, checksum mismatch; a journal record that does not
// fit the map).
MapSnapshot load_map_file(const std::filesystem::path& path);

}  // namespace heslam
