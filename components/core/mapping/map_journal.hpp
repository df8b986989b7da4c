// The map file's journal: what each save changed, appended to "<map file>.journal", so that saving the
// map after a keyframe costs what the keyframe changed, not what the map holds (issue 41).
//
// Layout (little-endian): header "HESLAMJL", u32 format version, u32 reserved, u64 checksum of the
// snapshot payload it extends (map_file.hpp); then records, each u64 payload bytes, payload, u64 FNV-1a
// checksum of the payload. A record holds the mapper state's scalars and the changes of its id tables,
// every keyframe the save's MapChanges name (pose, parent, covisibility, culled, map id; its features
// and point ids only when new or released by culling) and every changed or removed point. A keyframe's
// point ids otherwise follow from the points' observations (map_editing.hpp keeps the two directions
// equal), so replay unlinks a changed point's old observations and links its new ones.
//
// A record is written with one write(); a writer killed mid-record leaves an incomplete last record,
// which a reader detects (length, checksum), drops, and names in one warning. Compaction writes a new
// snapshot (renamed over the map file), which removes the journal; a new one naming the new snapshot
// follows. A journal naming another snapshot than the one beside it is stale and ignored.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/map_changes.hpp"
#include "components/core/mapping/map_file.hpp"
#include "components/core/mapping/mapper_state.hpp"

namespace heslam {

inline constexpr std::uint32_t kMapJournalFormatVersion = 1;

struct MapJournalOptions {
  // false: every save is a full snapshot (the behaviour before the journal).
  bool enabled = true;
  // A save whose record would make the journal larger than this x the snapshot writes a snapshot
  // instead: the journal never outgrows the snapshot, so the bytes written per keyframe stay at most
  // about (1 + 1 / ratio) x the record's on average, and a reload at most twice the snapshot.
  double compact_ratio = 1.0;
  bool sync = false;  // fsync every record and snapshot (durable across power loss, slower)
};

struct MapSaveStats {
  bool snapshot = false;    // this save wrote a full snapshot (compaction), else a journal record
  std::uint64_t bytes = 0;  // written by this save
  double serialize_ms = 0.0;
  double write_ms = 0.0;
  std::uint64_t snapshot_bytes = 0;  // the current snapshot's size
  std::uint64_t journal_bytes = 0;   // the current journal's size
};

// The writer: one per map file, in the process that owns the map (the local mapper).
class MapJournal {
 public:
  MapJournal(std::filesystem::path map_file, MapJournalOptions options);
  ~MapJournal();
  MapJournal(const MapJournal&) = delete;
  MapJournal& operator=(const MapJournal&) = delete;

  // Persists the map: `changes` are everything changed since the previous save (MapChanges::merge of
  // the steps). The first save of a process, and a save whose record would outgrow the snapshot
  // (compact_ratio), writes a full snapshot instead. Throws std::runtime_error naming the file.
  MapSaveStats save(const Map& map, const MapperState& state, const PinholeStereo* camera, const MapChanges& changes);
  // A full snapshot now; the journal restarts empty, or (keep_journal false: the last save, at exit)
  // is gone, leaving a plain snapshot.
  MapSaveStats compact(const Map& map, const MapperState& state, const PinholeStereo* camera, bool keep_journal = true);
  // Records appended since the last snapshot.
  std::uint64_t records() const { return records_; }

 private:
  void close_journal();

  std::filesystem::path map_file_;
  std::filesystem::path journal_file_;
  MapJournalOptions options_;
  int fd_ = -1;  // the journal, open for appending; -1 until the first snapshot
  std::uint64_t snapshot_bytes_ = 0;
  std::uint64_t journal_bytes_ = 0;
  std::uint64_t records_ = 0;
  // What the files hold of the state beyond the MapChanges (the id tables are diffed against these)
  // and how many keypoints each keyframe's stored features have.
  MapperState persisted_;
  std::map<KeyframeId, std::size_t> persisted_keypoints_;
};

// Applies the complete records of the journal at `journal` to `snapshot` (the map file's snapshot,
// whose payload checksum is `snapshot_checksum`); fills snapshot.journal. Returns false, applying
// nothing, when the journal names another snapshot; true otherwise (also when there is none). Throws
// std::runtime_error naming the journal when it is no journal or a record does not fit the map.
bool replay_map_journal(const std::filesystem::path& journal, std::uint64_t snapshot_checksum, MapSnapshot& snapshot);

// The first difference between two maps with their mapper state, as one line ("keyframe 3: T_wc"),
// or nothing when they are the same (equal snapshot payloads).
std::optional<std::string> first_map_difference(const Map& a, const MapperState& a_state, const Map& b,
                                                const MapperState& b_state);

}  // namespace heslam
