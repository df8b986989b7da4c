// The map file's journal: record writer, replay, and the map comparison that checks them.
#include "components/core/mapping/map_journal.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "components/core/map/ids.hpp"
#include "components/core/mapping/map_codec.hpp"
#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

using map_codec::Reader;
using map_codec::Writer;

constexpr char kJournalMagic[8] = {'H', 'E', 'S', 'L', 'A', 'M', 'J', 'L'};
constexpr std::size_t kJournalHeaderBytes = 8 + 4 + 4 + 8;
constexpr std::size_t kRecordFrameBytes = 8 + 8;  // length before, checksum after the payload

double elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

bool same_pose(const Pose3& a, const Pose3& b) { return a.matrix() == b.matrix(); }

// The entries of `now` that `persisted` lacks or holds with another value, and the keys `now` lacks;
// written as two lists, then `persisted` is made equal to `now`. A merge walk over both tables: no
// allocation but the lists, a few ns an entry.
template <typename Value, typename Equal, typename PutValue>
void put_table_changes(Writer& w, std::map<std::uint64_t, Value>& persisted, const std::map<std::uint64_t, Value>& now,
                       Equal equal, PutValue put_value) {
  std::vector<typename std::map<std::uint64_t, Value>::const_iterator> upserts;
  std::vector<std::uint64_t> erases;
  auto p = persisted.begin();
  auto n = now.begin();
  while (p != persisted.end() || n != now.end()) {
    if (n == now.end() || (p != persisted.end() && p->first < n->first)) {
      erases.push_back(p->first);
      ++p;
    } else if (p == persisted.end() || n->first < p->first) {
      upserts.push_back(n);
      ++n;
    } else {
      if (!equal(p->second, n->second)) upserts.push_back(n);
      ++p;
      ++n;
    }
  }
  w.put(static_cast<std::uint64_t>(upserts.size()));
  for (const auto& it : upserts) {
    w.put(it->first);
    put_value(it->second);
    persisted[it->first] = it->second;
  }
  w.put(static_cast<std::uint64_t>(erases.size()));
  for (const std::uint64_t key : erases) {
    w.put(key);
    persisted.erase(key);
  }
}

template <typename Value, typename GetValue>
void get_table_changes(Reader& r, std::map<std::uint64_t, Value>& table, std::size_t value_bytes, GetValue get_value) {
  for (std::uint64_t n = r.get_count(8 + value_bytes); n > 0; --n) {
    const auto key = r.get<std::uint64_t>();
    table[key] = get_value();
  }
  for (std::uint64_t n = r.get_count(8); n > 0; --n) table.erase(r.get<std::uint64_t>());
}

bool same_motion(const CorrectionMotion& a, const CorrectionMotion& b) {
  if (a.map_version != b.map_version || a.T_new_old.size() != b.T_new_old.size()) return false;
  auto ia = a.T_new_old.begin();
  for (auto ib = b.T_new_old.begin(); ib != b.T_new_old.end(); ++ia, ++ib) {
    if (ia->first != ib->first || !same_pose(ia->second, ib->second)) return false;
  }
  return true;
}

void put_motion(Writer& w, const CorrectionMotion& record) {
  w.put(record.map_version);
  w.put(static_cast<std::uint64_t>(record.T_new_old.size()));
  for (const auto& [id, T] : record.T_new_old) {
    w.put(id);
    w.put_pose(T);
  }
}

// The correction motions are a queue (oldest dropped first, new ones appended, the newest records
// extended by late keyframes): written as how many to drop from the front, how many of the rest to
// keep, and the records after those.
void put_motion_changes(Writer& w, std::vector<CorrectionMotion>& persisted, const std::vector<CorrectionMotion>& now) {
  std::size_t drop = persisted.size();
  if (!now.empty()) {
    for (std::size_t i = 0; i < persisted.size(); ++i) {
      if (persisted[i].map_version == now.front().map_version) {
        drop = i;
        break;
      }
    }
  }
  std::size_t keep = 0;
  while (drop + keep < persisted.size() && keep < now.size() && same_motion(persisted[drop + keep], now[keep])) ++keep;
  w.put(static_cast<std::uint64_t>(drop));
  w.put(static_cast<std::uint64_t>(keep));
  w.put(static_cast<std::uint64_t>(now.size() - keep));
  for (std::size_t i = keep; i < now.size(); ++i) put_motion(w, now[i]);
  persisted = now;
}

void get_motion_changes(Reader& r, std::vector<CorrectionMotion>& motions) {
  const auto drop = r.get<std::uint64_t>();
  const auto keep = r.get<std::uint64_t>();
  if (drop > motions.size() || keep > motions.size() - drop) {
    r.fail("correction motions: drop " + std::to_string(drop) + ", keep " + std::to_string(keep) + " of " +
           std::to_string(motions.size()));
  }
  motions.erase(motions.begin(), motions.begin() + static_cast<std::ptrdiff_t>(drop));
  motions.resize(keep);
  for (std::uint64_t n = r.get_count(16); n > 0; --n) {
    CorrectionMotion record;
    record.map_version = r.get<std::uint64_t>();
    for (std::uint64_t k = r.get_count(8 + 96); k > 0; --k) {
      const auto id = r.get<std::uint64_t>();
      record.T_new_old[id] = r.get_pose();
    }
    motions.push_back(std::move(record));
  }
}

void write_all(int fd, const std::uint8_t* data, std::size_t size, const std::filesystem::path& path) {
  while (size > 0) {
    const ssize_t written = ::write(fd, data, size);
    if (written < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error("map journal " + path.string() + ": cannot append: " + std::strerror(errno));
    }
    data += written;
    size -= static_cast<std::size_t>(written);
  }
}

// Record payload: the changes since the previous save (see the header comment for what is in it).
void put_record(Writer& w, const Map& map, const MapperState& state, const MapChanges& changes, MapperState& persisted,
                std::map<KeyframeId, std::size_t>& persisted_keypoints) {
  w.put(map.version);
  w.put(state.next_point_counter);
  w.put(state.keyframes_processed);
  w.put(state.last_keyframe);
  const auto equal = [](std::uint64_t a, std::uint64_t b) { return a == b; };
  const auto put_u64 = [&w](std::uint64_t value) { w.put(value); };
  put_table_changes(w, persisted.created_version, state.created_version, equal, put_u64);
  put_table_changes(w, persisted.recent_points, state.recent_points, equal, put_u64);
  put_table_changes(w, persisted.culled_T_pc, state.culled_T_pc, same_pose, [&w](const Pose3& T) { w.put_pose(T); });
  put_table_changes(w, persisted.merged_into, state.merged_into, equal, put_u64);
  put_motion_changes(w, persisted.correction_motions, state.correction_motions);

  std::vector<const Keyframe*> keyframes;
  for (const KeyframeId id : changes.changed_keyframes) {
    if (const Keyframe* kf = map.keyframe(id); kf != nullptr) keyframes.push_back(kf);
  }
  w.put(static_cast<std::uint64_t>(keyframes.size()));
  for (const Keyframe* kf : keyframes) {
    w.put(kf->id);
    w.put(kf->map_id);
    w.put(kf->stamp_ns);
    w.put_pose(kf->T_wc);
    w.put(kf->parent);
    w.put(static_cast<std::uint8_t>(kf->culled ? 1 : 0));
    w.put(static_cast<std::uint64_t>(kf->covisible.size()));
    for (const auto& [other, weight] : kf->covisible) {
      w.put(other);
      w.put(static_cast<std::int32_t>(weight));
    }
    // Features are immutable but for culling, which releases them: written when new or released.
    const auto stored = persisted_keypoints.find(kf->id);
    const bool with_features = stored == persisted_keypoints.end() || stored->second != kf->features.size();
    w.put(static_cast<std::uint8_t>(with_features ? 1 : 0));
    if (with_features) {
      map_codec::put_features(w, *kf);
      persisted_keypoints[kf->id] = kf->features.size();
    }
  }

  w.put(static_cast<std::uint64_t>(changes.removed_points.size()));
  for (const auto& [id, into] : changes.removed_points) w.put(id);
  std::vector<const MapPoint*> points;
  for (const PointId id : changes.changed_points) {
    if (const MapPoint* point = map.point(id); point != nullptr) points.push_back(point);
  }
  w.put(static_cast<std::uint64_t>(points.size()));
  for (const MapPoint* point : points) {
    map_codec::put_point(w, *point);
    w.put(point->map_id);
  }
}

// Keypoint `index` of keyframe `kf_id` observes `id` no longer (when it did).
void unlink(Map& map, PointId id, KeyframeId kf_id, int index) {
  Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || index < 0 || static_cast<std::size_t>(index) >= kf->point_ids.size()) return;
  if (kf->point_ids[static_cast<std::size_t>(index)] == id) kf->point_ids[static_cast<std::size_t>(index)] = kNoId;
}

void apply_record(Reader& r, MapSnapshot& snapshot) {
  Map& map = snapshot.map;
  MapperState& state = snapshot.state;
  r.context("mapper state");
  map.version = r.get<std::uint64_t>();
  state.next_point_counter = r.get<std::uint64_t>();
  state.keyframes_processed = r.get<std::uint64_t>();
  state.last_keyframe = r.get<std::uint64_t>();
  const auto get_u64 = [&r] { return r.get<std::uint64_t>(); };
  get_table_changes(r, state.created_version, 8, get_u64);
  get_table_changes(r, state.recent_points, 8, get_u64);
  get_table_changes(r, state.culled_T_pc, 96, [&r] { return r.get_pose(); });
  get_table_changes(r, state.merged_into, 8, get_u64);
  r.context("correction motions");
  get_motion_changes(r, state.correction_motions);

  const std::uint64_t keyframe_count = r.get_count(8 + 4 + 8 + 96 + 8 + 1 + 8 + 1);
  for (std::uint64_t k = 0; k < keyframe_count; ++k) {
    r.context("keyframe " + std::to_string(k) + " of " + std::to_string(keyframe_count));
    const auto id = r.get<std::uint64_t>();
    Keyframe* kf = map.keyframe(id);
    Keyframe added;
    Keyframe& target = kf != nullptr ? *kf : added;
    target.id = id;
    target.map_id = r.get<MapId>();
    target.stamp_ns = r.get<std::int64_t>();
    target.T_wc = r.get_pose();
    target.parent = r.get<std::uint64_t>();
    target.culled = r.get<std::uint8_t>() != 0;
    target.covisible.clear();
    for (std::uint64_t c = r.get_count(12); c > 0; --c) {
      const auto other = r.get<std::uint64_t>();
      target.covisible.emplace_back(other, r.get<std::int32_t>());
    }
    if (r.get<std::uint8_t>() != 0) {
      map_codec::get_features(r, target);
    } else if (kf == nullptr) {
      r.fail("keyframe " + format_id(id) + " is not in the map and comes without its features");
    }
    if (kf == nullptr) map.keyframes.emplace(id, std::move(added));
  }

  r.context("removed points");
  for (std::uint64_t n = r.get_count(8); n > 0; --n) {
    const auto id = r.get<std::uint64_t>();
    if (const MapPoint* point = map.point(id); point != nullptr) {
      for (const auto& [kf_id, index] : point->observations) unlink(map, id, kf_id, index);
      map.points.erase(id);
    }
  }
  const std::uint64_t point_count = r.get_count(map_codec::kPointMinBytes + 4);
  for (std::uint64_t k = 0; k < point_count; ++k) {
    r.context("point " + std::to_string(k) + " of " + std::to_string(point_count));
    MapPoint point = map_codec::get_point(r);
    point.map_id = r.get<MapId>();
    if (const MapPoint* old = map.point(point.id); old != nullptr) {
      for (const auto& [kf_id, index] : old->observations) unlink(map, point.id, kf_id, index);
    }
    for (const auto& [kf_id, index] : point.observations) {
      Keyframe* kf = map.keyframe(kf_id);
      if (kf == nullptr || index < 0 || static_cast<std::size_t>(index) >= kf->point_ids.size()) {
        r.fail("observation of unknown keyframe " + format_id(kf_id) + " keypoint " + std::to_string(index));
      }
      kf->point_ids[static_cast<std::size_t>(index)] = point.id;
    }
    map.points.insert_or_assign(point.id, std::move(point));
  }
  r.context("end of record");
  if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " unexpected trailing bytes");
}

}  // namespace

MapJournal::MapJournal(std::filesystem::path map_file, MapJournalOptions options)
    : map_file_(std::move(map_file)), journal_file_(map_journal_path(map_file_)), options_(options) {}

MapJournal::~MapJournal() { close_journal(); }

void MapJournal::close_journal() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

MapSaveStats MapJournal::compact(const Map& map, const MapperState& state, const PinholeStereo* camera,
                                 bool keep_journal) {
  close_journal();
  const MapFileWriteStats written = save_map_file(map_file_, map, state, options_.sync, camera);
  MapSaveStats stats;
  stats.snapshot = true;
  stats.bytes = written.bytes;
  stats.serialize_ms = written.serialize_ms;
  stats.write_ms = written.write_ms;
  snapshot_bytes_ = written.bytes;
  journal_bytes_ = 0;
  records_ = 0;
  if (options_.enabled && keep_journal) {
    const auto start = std::chrono::steady_clock::now();
    Writer header;
    header.buffer.insert(header.buffer.end(), kJournalMagic, kJournalMagic + sizeof(kJournalMagic));
    header.put(kMapJournalFormatVersion);
    header.put(std::uint32_t{0});
    header.put(written.checksum);
    try {
      runtime::replace_file_contents(
          journal_file_, {reinterpret_cast<const char*>(header.buffer.data()), header.buffer.size()}, options_.sync);
    } catch (const std::runtime_error& error) {
      throw std::runtime_error(std::string("map journal ") + error.what());
    }
    fd_ = ::open(journal_file_.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
    if (fd_ < 0) {
      throw std::runtime_error("map journal " + journal_file_.string() + ": cannot open: " + std::strerror(errno));
    }
    journal_bytes_ = header.buffer.size();
    persisted_ = state;
    persisted_keypoints_.clear();
    for (const auto& [id, kf] : map.keyframes)
      persisted_keypoints_.emplace_hint(persisted_keypoints_.end(), id, kf.features.size());
    stats.write_ms += elapsed_ms(start);
  }
  stats.snapshot_bytes = snapshot_bytes_;
  stats.journal_bytes = journal_bytes_;
  return stats;
}

MapSaveStats MapJournal::save(const Map& map, const MapperState& state, const PinholeStereo* camera,
                              const MapChanges& changes) {
  // The journal grew past the snapshot (compact_ratio): a snapshot now, so a reload replays at most
  // about one snapshot's worth of records.
  if (!options_.enabled || fd_ < 0 ||
      static_cast<double>(journal_bytes_) > options_.compact_ratio * static_cast<double>(snapshot_bytes_)) {
    return compact(map, state, camera);
  }
  const auto start = std::chrono::steady_clock::now();
  Writer record;
  record.put(std::uint64_t{0});  // the payload's length, known once it is written
  put_record(record, map, state, changes, persisted_, persisted_keypoints_);
  const std::uint64_t payload_bytes = record.buffer.size() - 8;
  std::memcpy(record.buffer.data(), &payload_bytes, sizeof(payload_bytes));
  record.put(map_codec::fnv1a(record.buffer.data() + 8, payload_bytes));
  MapSaveStats stats;
  stats.serialize_ms = elapsed_ms(start);
  const auto write_start = std::chrono::steady_clock::now();
  try {
    write_all(fd_, record.buffer.data(), record.buffer.size(), journal_file_);
    if (options_.sync && ::fsync(fd_) != 0) {
      throw std::runtime_error("map journal " + journal_file_.string() + ": cannot sync: " + std::strerror(errno));
    }
  } catch (...) {
    close_journal();  // the tables above already count the record: the next save is a snapshot
    throw;
  }
  stats.write_ms = elapsed_ms(write_start);
  journal_bytes_ += record.buffer.size();
  ++records_;
  stats.bytes = record.buffer.size();
  stats.snapshot_bytes = snapshot_bytes_;
  stats.journal_bytes = journal_bytes_;
  return stats;
}

bool replay_map_journal(const std::filesystem::path& journal, std::uint64_t snapshot_checksum, MapSnapshot& snapshot) {
  snapshot.journal = MapJournalReplay{};
  std::ifstream in(journal, std::ios::binary);
  if (!in) return true;  // none: the snapshot is the map
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < kJournalHeaderBytes) {
    // The header is written whole (renamed into place), so this is damage, not a torn append.
    snapshot.journal.dropped_bytes = bytes.size();
    snapshot.journal.warning = "map journal " + journal.string() + ": " + std::to_string(bytes.size()) +
                               " bytes, shorter than its header; ignored (the map is the snapshot's)";
    return true;
  }
  Reader header(journal, bytes.data(), bytes.size(), "map journal");
  if (std::memcmp(bytes.data(), kJournalMagic, sizeof(kJournalMagic)) != 0) {
    header.fail("not a heslam map journal (expected magic HESLAMJL)");
  }
  for (std::size_t i = 0; i < sizeof(kJournalMagic); ++i) header.get<char>();
  const auto format = header.get<std::uint32_t>();
  if (format != kMapJournalFormatVersion) {
    header.fail("format version " + std::to_string(format) + ", this build reads version " +
                std::to_string(kMapJournalFormatVersion));
  }
  header.get<std::uint32_t>();
  if (header.get<std::uint64_t>() != snapshot_checksum) {
    snapshot.journal.stale = true;
    return false;
  }
  std::size_t offset = kJournalHeaderBytes;
  while (offset < bytes.size()) {
    const std::size_t left = bytes.size() - offset;
    std::uint64_t payload_bytes = 0;
    bool complete = left >= kRecordFrameBytes;
    if (complete) {
      std::memcpy(&payload_bytes, bytes.data() + offset, sizeof(payload_bytes));
      complete = payload_bytes <= left - kRecordFrameBytes;
    }
    bool intact = false;
    if (complete) {
      const std::uint8_t* payload = bytes.data() + offset + 8;
      std::uint64_t stored = 0;
      std::memcpy(&stored, payload + payload_bytes, sizeof(stored));
      intact = map_codec::fnv1a(payload, payload_bytes) == stored;
    }
    if (!complete || !intact) {
      snapshot.journal.dropped_bytes = left;
      snapshot.journal.warning = "map journal " + journal.string() + ": record " +
                                 std::to_string(snapshot.journal.records + 1) +
                                 (complete ? " fails its checksum" : " is incomplete") + " (" + std::to_string(left) +
                                 " bytes at the end: an append cut short by a kill, or still being written); dropped, "
                                 "the map is the snapshot and the " +
                                 std::to_string(snapshot.journal.records) + " records before it";
      return true;
    }
    Reader record(journal, bytes.data() + offset + 8, payload_bytes, "map journal");
    record.context("record " + std::to_string(snapshot.journal.records + 1));
    apply_record(record, snapshot);
    ++snapshot.journal.records;
    offset += kRecordFrameBytes + payload_bytes;
  }
  return true;
}

std::optional<std::string> first_map_difference(const Map& a, const MapperState& a_state, const Map& b,
                                                const MapperState& b_state) {
  if (a.version != b.version) return "map version " + std::to_string(a.version) + " / " + std::to_string(b.version);
  if (a_state.next_point_counter != b_state.next_point_counter) return std::string("state next_point_counter");
  if (a_state.keyframes_processed != b_state.keyframes_processed) return std::string("state keyframes_processed");
  if (a_state.last_keyframe != b_state.last_keyframe) return std::string("state last_keyframe");
  if (a_state.created_version != b_state.created_version) return std::string("state created_version");
  if (a_state.recent_points != b_state.recent_points) return std::string("state recent_points");
  if (a_state.merged_into != b_state.merged_into) return std::string("state merged_into");
  if (a_state.culled_T_pc.size() != b_state.culled_T_pc.size()) return std::string("state culled_T_pc size");
  for (auto ia = a_state.culled_T_pc.begin(), ib = b_state.culled_T_pc.begin(); ia != a_state.culled_T_pc.end();
       ++ia, ++ib) {
    if (ia->first != ib->first || !same_pose(ia->second, ib->second))
      return "state culled_T_pc " + format_id(ia->first);
  }
  if (a_state.correction_motions.size() != b_state.correction_motions.size()) {
    return std::string("state correction_motions size");
  }
  for (std::size_t i = 0; i < a_state.correction_motions.size(); ++i) {
    if (!same_motion(a_state.correction_motions[i], b_state.correction_motions[i])) {
      return "state correction_motions " + std::to_string(i);
    }
  }
  for (const auto& [id, ka] : a.keyframes) {
    const Keyframe* kb = b.keyframe(id);
    const std::string name = "keyframe " + format_id(id) + ": ";
    if (kb == nullptr) return name + "missing";
    if (ka.map_id != kb->map_id) return name + "map_id";
    if (ka.stamp_ns != kb->stamp_ns) return name + "stamp";
    if (!same_pose(ka.T_wc, kb->T_wc)) return name + "T_wc";
    if (ka.parent != kb->parent) return name + "parent";
    if (ka.culled != kb->culled) return name + "culled";
    if (ka.covisible != kb->covisible) return name + "covisible";
    if (ka.point_ids != kb->point_ids) return name + "point_ids";
    Writer wa;
    Writer wb;
    map_codec::put_features(wa, ka);
    map_codec::put_features(wb, *kb);
    if (wa.buffer != wb.buffer) return name + "features";
  }
  if (a.keyframes.size() != b.keyframes.size()) return std::string("keyframe count");
  for (const auto& [id, pa] : a.points) {
    const MapPoint* pb = b.point(id);
    const std::string name = "point " + format_id(id) + ": ";
    if (pb == nullptr) return name + "missing";
    if (pa.map_id != pb->map_id) return name + "map_id";
    Writer wa;
    Writer wb;
    map_codec::put_point(wa, pa);
    map_codec::put_point(wb, *pb);
    if (wa.buffer != wb.buffer) return name + "state";
  }
  if (a.points.size() != b.points.size()) return std::string("point count");
  return std::nullopt;
}

}  // namespace heslam
