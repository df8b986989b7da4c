// heslam-occupancy's live outputs on the wire (idl/occupancy.idl): the 2D grid and the dense cloud
// <-> the core's OccupancyGrid and points. DDS-free, so the process, heslam-ros2-bridge and
// heslam-viewer share one layout and it is unit-tested on known grids.
//
// Layout: the grid message covers the bounding box of the known cells exactly as
// OccupancyGrid::write_map_server does (an empty grid: one unknown cell at the origin), rows from the
// lowest y up (nav_msgs/OccupancyGrid's order; the PGM's rows are the same, top row = largest y).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "runtime/messages.hpp"

namespace heslam::occupancy {

// Holds an OccupancyGrid2D and the storage its cells point into. Build one, write get(), drop it.
class GridMessage {
 public:
  // T_wg: grid frame -> world (the map's R_gw transposed, no translation).
  GridMessage(const OccupancyGrid& grid, const Pose3& T_wg, std::uint64_t revision, std::int64_t stamp_ns,
              std::uint32_t keyframes);
  GridMessage(const GridMessage&) = delete;
  GridMessage& operator=(const GridMessage&) = delete;
  const msg::OccupancyGrid2D& get() const { return message_; }

 private:
  std::vector<std::uint8_t> cells_;
  msg::OccupancyGrid2D message_{};
};

// The cells of a message, or a one-line reason it is malformed (size, resolution, cell values).
struct ReceivedGrid {
  OccupancyGrid grid;
  Pose3 T_wg = Pose3::Identity();
};
std::string check_grid(const msg::OccupancyGrid2D& message);  // empty when well-formed
// Throws std::runtime_error with check_grid's reason.
ReceivedGrid from_message(const msg::OccupancyGrid2D& message);

// Every k-th world point of `points` so that at most max_points are kept (k = ceil(n / max_points)).
std::vector<Eigen::Vector3f> decimate(const std::vector<Eigen::Vector3f>& points, std::size_t max_points);

class CloudMessage {
 public:
  CloudMessage(const std::vector<Eigen::Vector3f>& points_w, std::uint32_t total_points, std::uint64_t revision,
               std::int64_t stamp_ns, std::uint32_t keyframes);
  CloudMessage(const CloudMessage&) = delete;
  CloudMessage& operator=(const CloudMessage&) = delete;
  const msg::DenseCloud& get() const { return message_; }

 private:
  std::vector<float> xyz_;
  msg::DenseCloud message_{};
};

}  // namespace heslam::occupancy
