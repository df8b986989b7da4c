// Binary snapshot writer and validating reader of the map file.
#include "components/core/mapping/map_file.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "components/core/map/ids.hpp"
#include "components/core/mapping/map_codec.hpp"
#include "components/core/mapping/map_journal.hpp"
#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

using map_codec::kKeyframeMinBytes;
using map_codec::kKeypointBytes;
using map_codec::kPointMinBytes;
using map_codec::Reader;
using map_codec::Writer;

constexpr char kMagic[8] = {'H', 'E', 'S', 'L', 'A', 'M', 'A', 'P'};
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8;
constexpr std::size_t kChecksumBytes = 8;

double elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void write_payload(Writer& w, const Map& map, const MapperState& state, const PinholeStereo* camera) {
  w.put(map.version);
  w.put(state.next_point_counter);
  w.put(state.keyframes_processed);
  w.put(state.last_keyframe);
  w.put(static_cast<std::uint64_t>(state.created_version.size()));
  for (const auto& [id, version] : state.created_version) {
    w.put(id);
    w.put(version);
  }
  w.put(static_cast<std::uint64_t>(state.recent_points.size()));
  for (const auto& [id, seq] : state.recent_points) {
    w.put(id);
    w.put(seq);
  }
  w.put(static_cast<std::uint64_t>(state.culled_T_pc.size()));
  for (const auto& [id, T_pc] : state.culled_T_pc) {
    w.put(id);
    w.put_pose(T_pc);
  }
  w.put(static_cast<std::uint64_t>(state.merged_into.size()));
  for (const auto& [from, into] : state.merged_into) {
    w.put(from);
    w.put(into);
  }

  w.put(static_cast<std::uint64_t>(map.keyframes.size()));
  for (const auto& [id, kf] : map.keyframes) {
    w.put(kf.id);
    w.put(kf.stamp_ns);
    w.put_pose(kf.T_wc);
    w.put(kf.parent);
    w.put(static_cast<std::uint8_t>(kf.culled ? 1 : 0));
    map_codec::put_features(w, kf);
    w.put(static_cast<std::uint64_t>(kf.covisible.size()));
    for (const auto& [other, weight] : kf.covisible) {
      w.put(other);
      w.put(static_cast<std::int32_t>(weight));
    }
  }

  w.put(static_cast<std::uint64_t>(map.points.size()));
  for (const auto& [id, p] : map.points) {
    map_codec::put_point(w, p);
  }

  w.put(static_cast<std::uint64_t>(state.correction_motions.size()));
  for (const CorrectionMotion& record : state.correction_motions) {
    w.put(record.map_version);
    w.put(static_cast<std::uint64_t>(record.T_new_old.size()));
    for (const auto& [id, T] : record.T_new_old) {
      w.put(id);
      w.put_pose(T);
    }
  }

  // Format 3: map ids, listed only where not the first map's (a one-map file stays as it was, plus two
  // zero counts).
  std::vector<std::pair<std::uint64_t, MapId>> map_ids;
  for (const auto& [id, kf] : map.keyframes) {
    if (kf.map_id != kFirstMapId) map_ids.emplace_back(id, kf.map_id);
  }
  w.put(static_cast<std::uint64_t>(map_ids.size()));
  for (const auto& [id, map_id] : map_ids) {
    w.put(id);
    w.put(map_id);
  }
  map_ids.clear();
  for (const auto& [id, p] : map.points) {
    if (p.map_id != kFirstMapId) map_ids.emplace_back(id, p.map_id);
  }
  w.put(static_cast<std::uint64_t>(map_ids.size()));
  for (const auto& [id, map_id] : map_ids) {
    w.put(id);
    w.put(map_id);
  }

  // Format 4: the camera.
  w.put(static_cast<std::uint8_t>(camera != nullptr ? 1 : 0));
  if (camera != nullptr) {
    w.put(camera->fx_px);
    w.put(camera->fy_px);
    w.put(camera->cx_px);
    w.put(camera->cy_px);
    w.put(camera->baseline_m);
    w.put(static_cast<std::int32_t>(camera->width_px));
    w.put(static_cast<std::int32_t>(camera->height_px));
  }
}

void read_payload(Reader& r, std::uint32_t format, MapSnapshot& out) {
  Map& map = out.map;
  MapperState& state = out.state;
  r.context("mapper state");
  map.version = r.get<std::uint64_t>();
  state.next_point_counter = r.get<std::uint64_t>();
  state.keyframes_processed = r.get<std::uint64_t>();
  state.last_keyframe = r.get<std::uint64_t>();
  for (std::uint64_t n = r.get_count(16); n > 0; --n) {
    const auto id = r.get<std::uint64_t>();
    state.created_version[id] = r.get<std::uint64_t>();
  }
  for (std::uint64_t n = r.get_count(16); n > 0; --n) {
    const auto id = r.get<std::uint64_t>();
    state.recent_points[id] = r.get<std::uint64_t>();
  }
  for (std::uint64_t n = r.get_count(8 + 96); n > 0; --n) {
    const auto id = r.get<std::uint64_t>();
    state.culled_T_pc[id] = r.get_pose();
  }
  for (std::uint64_t n = r.get_count(16); n > 0; --n) {
    const auto from = r.get<std::uint64_t>();
    state.merged_into[from] = r.get<std::uint64_t>();
  }

  const std::uint64_t keyframe_count = r.get_count(kKeyframeMinBytes);
  for (std::uint64_t k = 0; k < keyframe_count; ++k) {
    r.context("keyframe " + std::to_string(k) + " of " + std::to_string(keyframe_count));
    Keyframe kf;
    kf.id = r.get<std::uint64_t>();
    kf.stamp_ns = r.get<std::int64_t>();
    kf.T_wc = r.get_pose();
    kf.parent = r.get<std::uint64_t>();
    kf.culled = r.get<std::uint8_t>() != 0;
    map_codec::get_features(r, kf);
    for (std::uint64_t c = r.get_count(12); c > 0; --c) {
      const auto other = r.get<std::uint64_t>();
      kf.covisible.emplace_back(other, r.get<std::int32_t>());
    }
    if (!map.keyframes.emplace(kf.id, std::move(kf)).second) r.fail("duplicate keyframe id");
  }

  const std::uint64_t point_count = r.get_count(kPointMinBytes);
  for (std::uint64_t k = 0; k < point_count; ++k) {
    r.context("point " + std::to_string(k) + " of " + std::to_string(point_count));
    MapPoint p = map_codec::get_point(r);
    for (const auto& [kf_id, index] : p.observations) {
      const Keyframe* kf = map.keyframe(kf_id);
      if (kf == nullptr || index < 0 || static_cast<std::size_t>(index) >= kf->point_ids.size()) {
        r.fail("observation of unknown keyframe " + format_id(kf_id) + " keypoint " + std::to_string(index));
      }
    }
    if (!map.points.emplace(p.id, std::move(p)).second) r.fail("duplicate point id");
  }
  if (format >= 2) {
    r.context("correction motions");
    for (std::uint64_t n = r.get_count(16); n > 0; --n) {
      CorrectionMotion record;
      record.map_version = r.get<std::uint64_t>();
      for (std::uint64_t k = r.get_count(8 + 96); k > 0; --k) {
        const auto id = r.get<std::uint64_t>();
        record.T_new_old[id] = r.get_pose();
      }
      state.correction_motions.push_back(std::move(record));
    }
  }
  if (format >= 3) {
    r.context("keyframe map ids");
    for (std::uint64_t n = r.get_count(12); n > 0; --n) {
      const auto id = r.get<std::uint64_t>();
      Keyframe* kf = map.keyframe(id);
      if (kf == nullptr) r.fail("map id of unknown keyframe " + format_id(id));
      kf->map_id = r.get<MapId>();
    }
    r.context("point map ids");
    for (std::uint64_t n = r.get_count(12); n > 0; --n) {
      const auto id = r.get<std::uint64_t>();
      MapPoint* p = map.point(id);
      if (p == nullptr) r.fail("map id of unknown point " + format_id(id));
      p->map_id = r.get<MapId>();
    }
  }
  if (format >= 4) {
    r.context("camera");
    if (r.get<std::uint8_t>() != 0) {
      PinholeStereo camera;
      camera.fx_px = r.get<double>();
      camera.fy_px = r.get<double>();
      camera.cx_px = r.get<double>();
      camera.cy_px = r.get<double>();
      camera.baseline_m = r.get<double>();
      camera.width_px = r.get<std::int32_t>();
      camera.height_px = r.get<std::int32_t>();
      if (!(camera.fx_px > 0.0) || !(camera.fy_px > 0.0) || !(camera.baseline_m > 0.0) || camera.width_px <= 0 ||
          camera.height_px <= 0) {
        r.fail("bad camera (" + describe_map_camera(camera) + ")");
      }
      out.camera = camera;
    }
  }
  r.context("end of payload");
  if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " unexpected trailing bytes");
}

}  // namespace

std::filesystem::path map_run_file_path(const std::filesystem::path& map_file) {
  std::filesystem::path path = map_file;
  path += ".run";
  return path;
}

std::filesystem::path map_journal_path(const std::filesystem::path& map_file) {
  std::filesystem::path path = map_file;
  path += ".journal";
  return path;
}

bool same_map_camera(const PinholeStereo& a, const PinholeStereo& b) {
  constexpr double kRelativeTolerance = 1e-6;  // the same calibration, rectified twice: equal to rounding
  const auto close = [](double x, double y) {
    return std::abs(x - y) <= kRelativeTolerance * std::max(1.0, std::abs(y));
  };
  return close(a.fx_px, b.fx_px) && close(a.fy_px, b.fy_px) && close(a.cx_px, b.cx_px) && close(a.cy_px, b.cy_px) &&
         close(a.baseline_m, b.baseline_m) && a.width_px == b.width_px && a.height_px == b.height_px;
}

std::string describe_map_camera(const PinholeStereo& camera) {
  std::ostringstream text;
  text << "fx " << camera.fx_px << " px, baseline " << camera.baseline_m << " m, " << camera.width_px << "x"
       << camera.height_px;
  return text.str();
}

std::vector<std::uint8_t> serialize_map_payload(const Map& map, const MapperState& state, const PinholeStereo* camera) {
  Writer payload;
  std::size_t estimate = 1024 + 128 * map.points.size();
  for (const auto& [id, kf] : map.keyframes) estimate += 256 + kKeypointBytes * kf.point_ids.size();
  payload.buffer.reserve(estimate);  // one allocation instead of repeated growth
  write_payload(payload, map, state, camera);
  return std::move(payload.buffer);
}

MapFileWriteStats save_map_file(const std::filesystem::path& path, const Map& map, const MapperState& state, bool sync,
                                const PinholeStereo* camera) {
  MapFileWriteStats stats;
  auto start = std::chrono::steady_clock::now();
  const std::vector<std::uint8_t> payload = serialize_map_payload(map, state, camera);
  Writer file;
  file.buffer.reserve(kHeaderBytes + payload.size() + kChecksumBytes);
  file.buffer.insert(file.buffer.end(), kMagic, kMagic + sizeof(kMagic));
  file.put(kMapFileFormatVersion);
  file.put(std::uint32_t{0});
  file.put(static_cast<std::uint64_t>(payload.size()));
  file.buffer.insert(file.buffer.end(), payload.begin(), payload.end());
  stats.checksum = map_codec::fnv1a(payload.data(), payload.size());
  file.put(stats.checksum);
  stats.serialize_ms = elapsed_ms(start);
  stats.bytes = file.buffer.size();

  start = std::chrono::steady_clock::now();
  try {
    runtime::replace_file_contents(path, {reinterpret_cast<const char*>(file.buffer.data()), file.buffer.size()}, sync);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("map file ") + error.what());
  }
  // The snapshot is the whole map: a journal beside it extends an earlier one (it names that one's
  // checksum and would be ignored anyway; removed so nothing stale stays behind).
  std::error_code ignored;
  std::filesystem::remove(map_journal_path(path), ignored);
  stats.write_ms = elapsed_ms(start);
  return stats;
}

namespace {

// The snapshot alone (no journal); `checksum`: its payload's, which a journal names as its base.
MapSnapshot load_snapshot(const std::filesystem::path& path, std::uint64_t& checksum) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("map file " + path.string() + ": cannot open");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Reader header(path, bytes.data(), bytes.size());
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throw std::runtime_error("map file " + path.string() + ": not a heslam map file (expected magic HESLAMAP)");
  }
  for (std::size_t i = 0; i < sizeof(kMagic); ++i) header.get<char>();
  const auto format = header.get<std::uint32_t>();
  if (format < kOldestReadableMapFileFormatVersion || format > kMapFileFormatVersion) {
    throw std::runtime_error("map file " + path.string() + ": format version " + std::to_string(format) +
                             ", this build reads versions " + std::to_string(kOldestReadableMapFileFormatVersion) +
                             " to " + std::to_string(kMapFileFormatVersion));
  }
  header.get<std::uint32_t>();
  const auto payload_bytes = header.get<std::uint64_t>();
  if (payload_bytes + kChecksumBytes != header.remaining()) {
    throw std::runtime_error("map file " + path.string() + ": truncated or padded: header announces " +
                             std::to_string(payload_bytes + kChecksumBytes) + " bytes after the header, file has " +
                             std::to_string(header.remaining()));
  }
  const std::uint8_t* payload = bytes.data() + kHeaderBytes;
  std::uint64_t stored_checksum;
  std::memcpy(&stored_checksum, payload + payload_bytes, sizeof(stored_checksum));
  if (map_codec::fnv1a(payload, payload_bytes) != stored_checksum) {
    throw std::runtime_error("map file " + path.string() + ": checksum mismatch (file corrupted)");
  }
  checksum = stored_checksum;
  MapSnapshot snapshot;
  Reader reader(path, payload, payload_bytes);
  read_payload(reader, format, snapshot);
  return snapshot;
}

}  // namespace

MapSnapshot load_map_file(const std::filesystem::path& path) {
  // A mapper compacting meanwhile (new snapshot, then a new journal naming it) can make the journal
  // read name another snapshot than the one read: read both again once. A journal that still names
  // another snapshot is stale (the mapper died between the two steps): the snapshot is the map.
  constexpr int kAttempts = 2;
  for (int attempt = 1;; ++attempt) {
    std::uint64_t checksum = 0;
    MapSnapshot snapshot = load_snapshot(path, checksum);
    if (replay_map_journal(map_journal_path(path), checksum, snapshot) || attempt == kAttempts) return snapshot;
  }
}

}  // namespace heslam
