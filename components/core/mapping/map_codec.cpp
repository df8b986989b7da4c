// The map's byte encoding (see map_codec.hpp).
#include "components/core/mapping/map_codec.hpp"

#include <stdexcept>

namespace heslam::map_codec {

std::uint64_t fnv1a(const std::uint8_t* data, std::size_t size) {
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a 64-bit offset basis and prime
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= data[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

void Writer::put_pose(const Pose3& T) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) put(T.matrix()(r, c));
  }
}

void Writer::put_vec(const Eigen::Vector3d& v) {
  put(v.x());
  put(v.y());
  put(v.z());
}

Pose3 Reader::get_pose() {
  Pose3 T = Pose3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) T.matrix()(r, c) = get<double>();
  }
  return T;
}

Eigen::Vector3d Reader::get_vec() {
  const double x = get<double>();
  const double y = get<double>();
  const double z = get<double>();
  return {x, y, z};
}

std::uint64_t Reader::get_count(std::size_t min_record_bytes) {
  const auto count = get<std::uint64_t>();
  if (min_record_bytes > 0 && count > (size_ - offset_) / min_record_bytes) {
    fail("count " + std::to_string(count) + " exceeds the remaining " + std::to_string(size_ - offset_) + " bytes");
  }
  return count;
}

void Reader::fail(const std::string& what) const {
  throw std::runtime_error(what_file_ + " " + path_.string() + ": " + what + " (" + context_ + ", offset " +
                           std::to_string(offset_) + ")");
}

void Reader::require(std::size_t bytes) const {
  if (bytes > size_ - offset_) {
    fail("truncated: need " + std::to_string(bytes) + " more bytes, " + std::to_string(size_ - offset_) + " left");
  }
}

void put_features(Writer& w, const Keyframe& kf) {
  const StereoFeatures& f = kf.features;
  w.put(static_cast<std::int32_t>(f.pyramid.levels));
  w.put(f.pyramid.scale_factor);
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
}

void get_features(Reader& r, Keyframe& kf) {
  const auto levels = r.get<std::int32_t>();
  const auto scale_factor = r.get<float>();
  if (levels < 1 || levels > 32 || !(scale_factor > 1.f)) {
    r.fail("bad pyramid " + std::to_string(levels) + " levels x " + std::to_string(scale_factor));
  }
  StereoFeatures& f = kf.features;
  f = StereoFeatures{};
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
    if (kp.octave < 0 || kp.octave >= levels) r.fail("keypoint octave " + std::to_string(kp.octave) + " out of range");
    f.u_right_px[i] = r.get<float>();
    f.depth_m[i] = r.get<float>();
    f.descriptors[i] = r.get<Descriptor>();
    kf.point_ids[i] = r.get<std::uint64_t>();
  }
}

void put_point(Writer& w, const MapPoint& p) {
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

MapPoint get_point(Reader& r) {
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
    p.observations.emplace_back(kf_id, index);
  }
  return p;
}

}  // namespace heslam::map_codec
