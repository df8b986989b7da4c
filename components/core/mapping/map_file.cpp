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
#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

constexpr char kMagic[8] = {'H', 'E', 'S', 'L', 'A', 'M', 'A', 'P'};
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8;
constexpr std::size_t kChecksumBytes = 8;

std::uint64_t fnv1a(const std::uint8_t* data, std::size_t size) {
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a 64-bit offset basis and prime
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= data[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

double elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

class Writer {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t offset = buffer.size();
    buffer.resize(offset + sizeof(T));
    std::memcpy(buffer.data() + offset, &value, sizeof(T));
  }
  void put_pose(const Pose3& T) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) put(T.matrix()(r, c));
    }
  }
  void put_vec(const Eigen::Vector3d& v) {
    put(v.x());
    put(v.y());
    put(v.z());
  }
  std::vector<std::uint8_t> buffer;
};

class Reader {
 public:
  Reader(const std::filesystem::path& path, const std::uint8_t* data, std::size_t size)
      : path_(path), data_(data), size_(size) {}

  void context(std::string what) { context_ = std::move(what); }

  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    require(sizeof(T));
    T value;
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  Pose3 get_pose() {
    Pose3 T = Pose3::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) T.matrix()(r, c) = get<double>();
    }
    return T;
  }
  Eigen::Vector3d get_vec() {
    const double x = get<double>();
    const double y = get<double>();
    const double z = get<double>();
    return {x, y, z};
  }
  // A record count, checked against the bytes left so a corrupt count cannot trigger a huge allocation.
  std::uint64_t get_count(std::size_t min_record_bytes) {
    const auto count = get<std::uint64_t>();
    if (min_record_bytes > 0 && count > (size_ - offset_) / min_record_bytes) {
      fail("count " + std::to_string(count) + " exceeds the remaining " + std::to_string(size_ - offset_) + " bytes");
    }
    return count;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error("map file " + path_.string() + ": " + what + " (" + context_ + ", offset " +
                             std::to_string(offset_) + ")");
  }
  std::size_t remaining() const { return size_ - offset_; }

 private:
  void require(std::size_t bytes) const {
    if (bytes > size_ - offset_) {
      fail("truncated: need " + std::to_string(bytes) + " more bytes, " + std::to_string(size_ - offset_) + " left");
    }
  }
  const std::filesystem::path& path_;
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  std::string context_ = "header";
};

// Minimum serialized sizes, for the count checks.
constexpr std::size_t kKeypointBytes = 4 * 4 + 4 + 4 + 4 + 32 + 8;
constexpr std::size_t kKeyframeMinBytes = 8 + 8 + 96 + 8 + 1 + 4 + 4 + 8 + 8;
constexpr std::size_t kPointMinBytes = 8 + 24 + 32 + 24 + 4 + 4 + 8 + 4 + 4 + 1 + 8 + 8;

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
    w.put(static_cast<std::int32_t>(kf.features.pyramid.levels));
    w.put(kf.features.pyramid.scale_factor);
    const StereoFeatures& f = kf.features;
    w.put(static_cast<std::uint64_t>(f.size()));
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Keypoint& kp = f.keypoints[i];
      w.put(kp.u_px);
      w.put(kp.v_px);
      w.put(kp.angle_deg);
      w.put(kp.response);
      w.put(static_cast<std::int32_t>(kp.octave));
      w.put(f.u_right_px[i]);
      w.put(f.depth_m[i]);
      w.put(f.descriptors[i]);
      w.put(kf.point_ids[i]);
    }
    w.put(static_cast<std::uint64_t>(kf.covisible.size()));
    for (const auto& [other, weight] : kf.covisible) {
      w.put(other);
      w.put(static_cast<std::int32_t>(weight));
    }
  }

  w.put(static_cast<std::uint64_t>(map.points.size()));
  for (const auto& [id, p] : map.points) {
    w.put(p.id);
    w.put_vec(p.p_w);
    w.put(p.descriptor);
    w.put_vec(p.normal);
    w.put(p.min_distance_m);
    w.put(p.max_distance_m);
    w.put(p.reference_kf);
    w.put(static_cast<std::int32_t>(p.visible));
    w.put(static_cast<std::int32_t>(p.found));
    w.put(static_cast<std::uint8_t>(p.culled ? 1 : 0));
    w.put(p.merged_into);
    w.put(static_cast<std::uint64_t>(p.observations.size()));
    for (const auto& [kf_id, index] : p.observations) {
      w.put(kf_id);
      w.put(static_cast<std::int32_t>(index));
    }
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
    const auto levels = r.get<std::int32_t>();
    const auto scale_factor = r.get<float>();
    if (levels < 1 || levels > 32 || !(scale_factor > 1.f)) {
      r.fail("bad pyramid " + std::to_string(levels) + " levels x " + std::to_string(scale_factor));
    }
    StereoFeatures& f = kf.features;
    f.pyramid = ScalePyramid::make(levels, scale_factor);
    const std::uint64_t n = r.get_count(kKeypointBytes);
    f.keypoints.resize(n);
    f.u_right_px.resize(n);
    f.depth_m.resize(n);
    f.descriptors.resize(n);
    kf.point_ids.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      Keypoint& kp = f.keypoints[i];
      kp.u_px = r.get<float>();
      kp.v_px = r.get<float>();
      kp.angle_deg = r.get<float>();
      kp.response = r.get<float>();
      kp.octave = r.get<std::int32_t>();
      if (kp.octave < 0 || kp.octave >= levels)
        r.fail("keypoint octave " + std::to_string(kp.octave) + " out of range");
      f.u_right_px[i] = r.get<float>();
      f.depth_m[i] = r.get<float>();
      f.descriptors[i] = r.get<Descriptor>();
      kf.point_ids[i] = r.get<std::uint64_t>();
    }
    for (std::uint64_t c = r.get_count(12); c > 0; --c) {
      const auto other = r.get<std::uint64_t>();
      kf.covisible.emplace_back(other, r.get<std::int32_t>());
    }
    if (!map.keyframes.emplace(kf.id, std::move(kf)).second) r.fail("duplicate keyframe id");
  }

  const std::uint64_t point_count = r.get_count(kPointMinBytes);
  for (std::uint64_t k = 0; k < point_count; ++k) {
    r.context("point " + std::to_string(k) + " of " + std::to_string(point_count));
    MapPoint p;
    p.id = r.get<std::uint64_t>();
    p.p_w = r.get_vec();
    p.descriptor = r.get<Descriptor>();
    p.normal = r.get_vec();
    p.min_distance_m = r.get<float>();
    p.max_distance_m = r.get<float>();
    p.reference_kf = r.get<std::uint64_t>();
    p.visible = r.get<std::int32_t>();
    p.found = r.get<std::int32_t>();
    p.culled = r.get<std::uint8_t>() != 0;
    p.merged_into = r.get<std::uint64_t>();
    for (std::uint64_t n = r.get_count(12); n > 0; --n) {
      const auto kf_id = r.get<std::uint64_t>();
      const auto index = r.get<std::int32_t>();
      const Keyframe* kf = map.keyframe(kf_id);
      if (kf == nullptr || index < 0 || static_cast<std::size_t>(index) >= kf->point_ids.size()) {
        r.fail("observation of unknown keyframe " + format_id(kf_id) + " keypoint " + std::to_string(index));
      }
      p.observations.emplace_back(kf_id, index);
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

MapFileWriteStats save_map_file(const std::filesystem::path& path, const Map& map, const MapperState& state, bool sync,
                                const PinholeStereo* camera) {
  MapFileWriteStats stats;
  auto start = std::chrono::steady_clock::now();
  Writer payload;
  std::size_t estimate = 1024 + 128 * map.points.size();
  for (const auto& [id, kf] : map.keyframes) estimate += 256 + kKeypointBytes * kf.point_ids.size();
  payload.buffer.reserve(estimate);  // one allocation instead of repeated growth
  write_payload(payload, map, state, camera);
  Writer file;
  file.buffer.reserve(kHeaderBytes + payload.buffer.size() + kChecksumBytes);
  file.buffer.insert(file.buffer.end(), kMagic, kMagic + sizeof(kMagic));
  file.put(kMapFileFormatVersion);
  file.put(std::uint32_t{0});
  file.put(static_cast<std::uint64_t>(payload.buffer.size()));
  file.buffer.insert(file.buffer.end(), payload.buffer.begin(), payload.buffer.end());
  file.put(fnv1a(payload.buffer.data(), payload.buffer.size()));
  stats.serialize_ms = elapsed_ms(start);
  stats.bytes = file.buffer.size();

  start = std::chrono::steady_clock::now();
  try {
    runtime::replace_file_contents(path, {reinterpret_cast<const char*>(file.buffer.data()), file.buffer.size()}, sync);
  } catch (const std::runtime_error& error) {
    throw std::runtime_error(std::string("map file ") + error.what());
  }
  stats.write_ms = elapsed_ms(start);
  return stats;
}

MapSnapshot load_map_file(const std::filesystem::path& path) {
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
  if (fnv1a(payload, payload_bytes) != stored_checksum) {
    throw std::runtime_error("map file " + path.string() + ": checksum mismatch (file corrupted)");
  }
  MapSnapshot snapshot;
  Reader reader(path, payload, payload_bytes);
  read_payload(reader, format, snapshot);
  return snapshot;
}

}  // namespace heslam
