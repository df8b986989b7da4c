// The keyframe-anchored occupancy map (see occupancy_map.hpp).
#include "components/core/occupancy/occupancy_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

constexpr char kCloudMagic[8] = {'H', 'E', 'S', 'O', 'C', 'C', '0', '2'};

Eigen::Matrix3d rotation_for(UpAxis up) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (up == UpAxis::kMinusY) R << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // grid (x, z, -y): right-handed
  if (up == UpAxis::kY) R << 1, 0, 0, 0, 0, -1, 0, 1, 0;       // grid (x, -z, y)
  return R;
}

template <typename T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

}  // namespace

UpAxis parse_up_axis(const std::string& name) {
  if (name == "-y") return UpAxis::kMinusY;
  if (name == "y") return UpAxis::kY;
  if (name == "z") return UpAxis::kZ;
  throw std::invalid_argument("up axis '" + name + "': expected -y, y or z");
}

const char* to_string(UpAxis up) {
  switch (up) {
    case UpAxis::kMinusY: return "-y";
    case UpAxis::kY: return "y";
    case UpAxis::kZ: return "z";
  }
  return "?";
}

Eigen::Vector3d up_direction(UpAxis up) { return rotation_for(up).transpose() * Eigen::Vector3d::UnitZ(); }

OccupancyMap::OccupancyMap(const OccupancyMapOptions& options)
    : options_(options), R_gw_(rotation_for(options.up)), voxels_(options.voxels) {
  if (!(options.band.min_m < options.band.max_m)) throw std::invalid_argument("occupancy: band min must be < max");
}

bool OccupancyMap::set_up_direction(const Eigen::Vector3d& up_w) {
  if (!up_w.allFinite() || std::abs(up_w.norm() - 1.0) > 1e-6) return false;
  const Eigen::Matrix3d R_base = rotation_for(options_.up);
  const Eigen::Quaterniond level = Eigen::Quaterniond::FromTwoVectors(R_base * up_w, Eigen::Vector3d::UnitZ());
  R_gw_ = level.toRotationMatrix() * R_base;
  voxels_.clear();
  fused_.clear();
  stale_ = false;
  return true;
}

double OccupancyMap::angle_to_up(const Eigen::Vector3d& up_w) const {
  return std::acos(std::clamp((R_gw_ * up_w).z(), -1.0, 1.0));
}

bool OccupancyMap::set_pose(std::uint64_t id, const Pose3& T_wc) {
  if (!T_wc.matrix().allFinite()) return false;
  poses_[id] = T_wc;
  const auto fused = fused_.find(id);
  if (fused != fused_.end()) {
    const Pose3 delta = fused->second.inverse() * T_wc;
    const double angle = Eigen::AngleAxisd(delta.rotation()).angle();
    if (delta.translation().norm() > options_.stale_translation_m || angle > options_.stale_rotation_rad) {
      stale_ = true;
    }
  }
  return true;
}

void OccupancyMap::cull(std::uint64_t id) {
  culled_[id] = true;
  clouds_.erase(id);
  if (fused_.erase(id) != 0) stale_ = true;
}

void OccupancyMap::add_cloud(std::uint64_t id, KeyframeCloud cloud) {
  if (culled(id)) return;
  clouds_[id] = std::move(cloud);
  if (fused_.erase(id) != 0) stale_ = true;  // a cloud replaced: rebuild without the old one
}

void OccupancyMap::fuse(std::uint64_t id, const KeyframeCloud& cloud, const Pose3& T_wc) {
  const Eigen::Matrix3f R = (R_gw_ * T_wc.rotation()).cast<float>();
  const Eigen::Vector3f t = (R_gw_ * T_wc.translation()).cast<float>();
  std::vector<Eigen::Vector3f> points_g;
  std::vector<float> sigmas;
  points_g.reserve(cloud.points_c.size());
  for (const Eigen::Vector3f& p : cloud.points_c) points_g.push_back(R * p + t);
  if (cloud.sigma_per_m2 > 0.f) {
    sigmas.reserve(cloud.points_c.size());
    for (const Eigen::Vector3f& p : cloud.points_c) sigmas.push_back(cloud.sigma_per_m2 * p.norm() * std::abs(p.z()));
  }
  std::vector<Eigen::Vector3f> normals_g;
  if (cloud.normals_c.size() == cloud.points_c.size()) {
    normals_g.reserve(cloud.normals_c.size());
    for (const Eigen::Vector3f& n : cloud.normals_c) normals_g.push_back(R * n);
  }
  voxels_.integrate((R_gw_ * T_wc.translation()), points_g, sigmas, normals_g);
  fused_[id] = T_wc;
}

void OccupancyMap::fuse_pending() {
  for (const auto& [id, cloud] : clouds_) {
    if (fused_.count(id)) continue;
    const auto pose = poses_.find(id);
    if (pose != poses_.end()) fuse(id, cloud, pose->second);
  }
}

void OccupancyMap::rebuild() {
  voxels_.clear();
  fused_.clear();
  stale_ = false;
  fuse_pending();
}

std::size_t OccupancyMap::cloud_points() const {
  std::size_t n = 0;
  for (const auto& [id, cloud] : clouds_) n += cloud.points_c.size();
  return n;
}

std::size_t OccupancyMap::write_ply(const std::filesystem::path& file) const {
  std::string body;
  std::size_t count = 0;
  for (const auto& [id, cloud] : clouds_) {
    const auto pose = poses_.find(id);
    if (pose == poses_.end()) continue;
    const Eigen::Matrix3f R = pose->second.rotation().cast<float>();
    const Eigen::Vector3f t = pose->second.translation().cast<float>();
    for (const Eigen::Vector3f& p : cloud.points_c) {
      const Eigen::Vector3f w = R * p + t;
      put(body, w.x());
      put(body, w.y());
      put(body, w.z());
      ++count;
    }
  }
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment heslam-occupancy dense cloud, world frame\n"
      "element vertex " +
      std::to_string(count) + "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  runtime::replace_file_contents(file, header + body, /*sync=*/false);
  return count;
}

void write_cloud(const std::filesystem::path& file, std::uint64_t id, const KeyframeCloud& cloud) {
  std::string out(kCloudMagic, sizeof(kCloudMagic));
  put(out, id);
  put(out, cloud.stamp_ns);
  put(out, static_cast<std::uint64_t>(cloud.points_c.size()));
  put(out, cloud.sigma_per_m2);
  const bool with_normals = !cloud.normals_c.empty() && cloud.normals_c.size() == cloud.points_c.size();
  put(out, static_cast<std::uint32_t>(with_normals ? 1 : 0));
  for (const Eigen::Vector3f& p : cloud.points_c) {
    put(out, p.x());
    put(out, p.y());
    put(out, p.z());
  }
  if (with_normals) {
    for (const Eigen::Vector3f& n : cloud.normals_c) {
      put(out, n.x());
      put(out, n.y());
      put(out, n.z());
    }
  }
  runtime::replace_file_contents(file, out, /*sync=*/false);
}

KeyframeCloud read_cloud(const std::filesystem::path& file, std::uint64_t& id) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  constexpr std::size_t kHeader =
      sizeof(kCloudMagic) + 3 * sizeof(std::uint64_t) + sizeof(float) + sizeof(std::uint32_t);
  if (bytes.size() < kHeader || std::memcmp(bytes.data(), kCloudMagic, sizeof(kCloudMagic)) != 0) {
    throw std::runtime_error(file.string() + ": not a heslam-occupancy keyframe cloud (magic HESOCC02)");
  }
  KeyframeCloud cloud;
  std::uint64_t count = 0;
  const char* at = bytes.data() + sizeof(kCloudMagic);
  std::memcpy(&id, at, sizeof(id));
  std::memcpy(&cloud.stamp_ns, at + 8, sizeof(cloud.stamp_ns));
  std::memcpy(&count, at + 16, sizeof(count));
  std::memcpy(&cloud.sigma_per_m2, at + 24, sizeof(cloud.sigma_per_m2));
  std::uint32_t with_normals = 0;
  std::memcpy(&with_normals, at + 28, sizeof(with_normals));
  if (with_normals > 1) throw std::runtime_error(file.string() + ": normals flag " + std::to_string(with_normals));
  if (!(cloud.sigma_per_m2 >= 0.f) || !std::isfinite(cloud.sigma_per_m2)) {
    throw std::runtime_error(file.string() + ": sigma_per_m2 " + std::to_string(cloud.sigma_per_m2) +
                             " is not a finite number >= 0");
  }
  const std::size_t expected = kHeader + count * 3 * sizeof(float) * (with_normals ? 2 : 1);
  if (bytes.size() != expected) {
    throw std::runtime_error(file.string() + ": " + std::to_string(bytes.size()) + " bytes, expected " +
                             std::to_string(expected) + " for " + std::to_string(count) + " points");
  }
  cloud.points_c.resize(count);
  const char* points = bytes.data() + kHeader;
  for (std::uint64_t i = 0; i < count; ++i) {
    float xyz[3];
    std::memcpy(xyz, points + i * sizeof(xyz), sizeof(xyz));
    cloud.points_c[i] = {xyz[0], xyz[1], xyz[2]};
  }
  if (with_normals) {
    cloud.normals_c.resize(count);
    const char* normals = points + count * 3 * sizeof(float);
    for (std::uint64_t i = 0; i < count; ++i) {
      float xyz[3];
      std::memcpy(xyz, normals + i * sizeof(xyz), sizeof(xyz));
      cloud.normals_c[i] = {xyz[0], xyz[1], xyz[2]};
    }
  }
  return cloud;
}

}  // namespace heslam
