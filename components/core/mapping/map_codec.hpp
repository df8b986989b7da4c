// The byte encoding shared by the map file (map_file.hpp) and its journal (map_journal.hpp): a
// little-endian writer and a bounds-checked reader, the FNV-1a checksum, and the layouts of a keyframe's
// features and of a map point, so that a snapshot and a journal record encode them the same way.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "components/core/map/map.hpp"

namespace heslam::map_codec {

std::uint64_t fnv1a(const std::uint8_t* data, std::size_t size);

class Writer {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t offset = buffer.size();
    buffer.resize(offset + sizeof(T));
    std::memcpy(buffer.data() + offset, &value, sizeof(T));
  }
  void put_pose(const Pose3& T);
  void put_vec(const Eigen::Vector3d& v);
  std::vector<std::uint8_t> buffer;
};

// Reads what Writer wrote; every shortfall or bad value throws std::runtime_error
// "<what_file> <path>: <what> (<context>, offset N)".
class Reader {
 public:
  Reader(const std::filesystem::path& path, const std::uint8_t* data, std::size_t size,
         std::string what_file = "map file")
      : path_(path), data_(data), size_(size), what_file_(std::move(what_file)) {}

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
  Pose3 get_pose();
  Eigen::Vector3d get_vec();
  // A record count, checked against the bytes left so a corrupt count cannot trigger a huge allocation.
  std::uint64_t get_count(std::size_t min_record_bytes);
  [[noreturn]] void fail(const std::string& what) const;
  std::size_t remaining() const { return size_ - offset_; }
  std::size_t offset() const { return offset_; }

 private:
  void require(std::size_t bytes) const;
  const std::filesystem::path& path_;
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  std::string what_file_;
  std::string context_ = "header";
};

// Minimum serialized sizes, for the count checks.
inline constexpr std::size_t kKeypointBytes = 4 * 4 + 4 + 4 + 4 + 32 + 8;
inline constexpr std::size_t kKeyframeMinBytes = 8 + 8 + 96 + 8 + 1 + 4 + 4 + 8 + 8;
inline constexpr std::size_t kPointMinBytes = 8 + 24 + 32 + 24 + 4 + 4 + 8 + 4 + 4 + 1 + 8 + 8;

// A keyframe's pyramid, keypoints (with stereo, descriptor) and point_ids: the bulk of a map, written
// once per keyframe by the journal (again only when culling releases them).
void put_features(Writer& w, const Keyframe& kf);
void get_features(Reader& r, Keyframe& kf);

// A map point without its map id (the snapshot stores map ids apart, format 3). get_point does not
// check the observations against the map: the caller does.
void put_point(Writer& w, const MapPoint& p);
MapPoint get_point(Reader& r);

}  // namespace heslam::map_codec
