// heslam-occupancy's live outputs on the wire (see occupancy_messages.hpp).
#include "components/occupancy/occupancy_messages.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::occupancy {
namespace {

// Far beyond any map this process makes (a 5 cm grid 100 km wide), small enough that width * height
// cannot overflow.
constexpr std::uint64_t kMaxCells = std::uint64_t{1} << 32;

std::uint8_t wire_value(CellState state) {
  switch (state) {
    case CellState::kFree: return heslam_msg_OCCUPANCY_FREE;
    case CellState::kOccupied: return heslam_msg_OCCUPANCY_OCCUPIED;
    case CellState::kUnknown: break;
  }
  return heslam_msg_OCCUPANCY_UNKNOWN;
}

}  // namespace

GridMessage::GridMessage(const OccupancyGrid& grid, const Pose3& T_wg, std::uint64_t revision, std::int64_t stamp_ns,
                         std::uint32_t keyframes) {
  // The bounding box of the known cells, as write_map_server takes it.
  int min_i = 0, max_i = 0, min_j = 0, max_j = 0;
  const auto& cells = grid.cells();
  if (!cells.empty()) {
    min_i = max_i = cells.begin()->first.first;
    min_j = max_j = cells.begin()->first.second;
    for (const auto& [index, state] : cells) {
      min_i = std::min(min_i, index.first);
      max_i = std::max(max_i, index.first);
      min_j = std::min(min_j, index.second);
      max_j = std::max(max_j, index.second);
    }
  }
  const std::size_t width = static_cast<std::size_t>(max_i - min_i + 1);
  const std::size_t height = static_cast<std::size_t>(max_j - min_j + 1);
  cells_.assign(width * height, heslam_msg_OCCUPANCY_UNKNOWN);
  for (const auto& [index, state] : cells) {
    const std::size_t row = static_cast<std::size_t>(index.second - min_j);
    const std::size_t col = static_cast<std::size_t>(index.first - min_i);
    cells_[row * width + col] = wire_value(state);
  }
  message_.revision = revision;
  message_.stamp_ns = stamp_ns;
  message_.keyframes = keyframes;
  message_.resolution_m = grid.resolution_m();
  message_.T_wg = messages::to_message(T_wg);
  message_.origin_i = min_i;
  message_.origin_j = min_j;
  message_.width = static_cast<std::uint32_t>(width);
  message_.height = static_cast<std::uint32_t>(height);
  runtime::borrow(message_.cells, cells_);
}

std::string check_grid(const msg::OccupancyGrid2D& message) {
  if (!(std::isfinite(message.resolution_m) && message.resolution_m > 0.0)) {
    return "field resolution_m: " + std::to_string(message.resolution_m) + ", expected a positive number";
  }
  const std::uint64_t expected = std::uint64_t{message.width} * message.height;
  if (expected > kMaxCells) {
    return "fields width, height: " + std::to_string(message.width) + " x " + std::to_string(message.height) +
           " cells, more than any map";
  }
  if (message.cells._length != expected) {
    return "field cells: " + std::to_string(message.cells._length) +
           " values, width x height = " + std::to_string(expected);
  }
  for (const std::uint8_t value : runtime::view(message.cells)) {
    if (value != heslam_msg_OCCUPANCY_FREE && value != heslam_msg_OCCUPANCY_OCCUPIED &&
        value != heslam_msg_OCCUPANCY_UNKNOWN) {
      return "field cells: value " + std::to_string(value) + ", expected 0 (free), 100 (occupied) or 255 (unknown)";
    }
  }
  for (const double v : message.T_wg.position_m) {
    if (!std::isfinite(v)) return "field T_wg: non-finite position";
  }
  for (const double v : message.T_wg.orientation_xyzw) {
    if (!std::isfinite(v)) return "field T_wg: non-finite orientation";
  }
  return {};
}

ReceivedGrid from_message(const msg::OccupancyGrid2D& message) {
  if (const std::string problem = check_grid(message); !problem.empty()) throw std::runtime_error(problem);
  ReceivedGrid received{OccupancyGrid(message.resolution_m), messages::to_pose(message.T_wg)};
  const auto cells = runtime::view(message.cells);
  for (std::uint32_t row = 0; row < message.height; ++row) {
    for (std::uint32_t col = 0; col < message.width; ++col) {
      const std::uint8_t value = cells[std::size_t{row} * message.width + col];
      if (value == heslam_msg_OCCUPANCY_UNKNOWN) continue;
      received.grid.set(message.origin_i + static_cast<int>(col), message.origin_j + static_cast<int>(row),
                        value == heslam_msg_OCCUPANCY_OCCUPIED ? CellState::kOccupied : CellState::kFree);
    }
  }
  return received;
}

std::vector<Eigen::Vector3f> decimate(const std::vector<Eigen::Vector3f>& points, std::size_t max_points) {
  if (max_points == 0) return {};
  if (points.size() <= max_points) return points;
  const std::size_t step = (points.size() + max_points - 1) / max_points;
  std::vector<Eigen::Vector3f> kept;
  kept.reserve(points.size() / step + 1);
  for (std::size_t i = 0; i < points.size(); i += step) kept.push_back(points[i]);
  return kept;
}

CloudMessage::CloudMessage(const std::vector<Eigen::Vector3f>& points_w, std::uint32_t total_points,
                           std::uint64_t revision, std::int64_t stamp_ns, std::uint32_t keyframes) {
  xyz_.reserve(points_w.size() * 3);
  for (const Eigen::Vector3f& p : points_w) xyz_.insert(xyz_.end(), {p.x(), p.y(), p.z()});
  message_.revision = revision;
  message_.stamp_ns = stamp_ns;
  message_.keyframes = keyframes;
  message_.total_points = total_points;
  runtime::borrow(message_.xyz_w_m, xyz_);
}

}  // namespace heslam::occupancy
