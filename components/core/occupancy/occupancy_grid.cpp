// The 2D grid and its map_server files (see occupancy_grid.hpp).
#include "components/core/occupancy/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <set>
#include <vector>

#include "runtime/atomic_file.hpp"

namespace heslam {
namespace {

// map_server's trinary values with negate 0: p = (255 - value) / 255, occupied above 0.65, free below 0.196.
constexpr std::uint8_t kOccupiedValue = 0;
constexpr std::uint8_t kFreeValue = 254;
constexpr std::uint8_t kUnknownValue = 205;
constexpr double kOccupiedThresh = 0.65;
constexpr double kFreeThresh = 0.196;

}  // namespace

OccupancyGrid OccupancyGrid::from_voxels(const VoxelMap& voxels, const GridBand& band) {
  OccupancyGrid grid(voxels.options().resolution_m);
  std::set<std::pair<int, int>> near;  // columns with a voxel near a surface: never free
  // The layers whose voxel centres may lie in the band (centre of layer k: (k + 1/2) resolution; one more
  // each side against rounding, the centre test below decides).
  const double r = voxels.options().resolution_m;
  const int min_layer = static_cast<int>(std::floor(band.min_m / r - 0.5));
  const int max_layer = static_cast<int>(std::ceil(band.max_m / r - 0.5));
  voxels.for_each_state(
      [&](const VoxelIndex& v, VoxelMap::VoxelState state) {
        const double z = voxels.center_of(v).z();
        if (z < band.min_m || z > band.max_m) return;
        CellState& cell = grid.cells_[{v.x, v.y}];
        if (state == VoxelMap::VoxelState::kOccupied) {
          cell = CellState::kOccupied;
        } else if (state == VoxelMap::VoxelState::kFree && cell != CellState::kOccupied) {
          cell = CellState::kFree;
        } else if (state == VoxelMap::VoxelState::kNear) {
          near.insert({v.x, v.y});
        }
      },
      min_layer, max_layer);
  for (const auto& column : near) {
    CellState& cell = grid.cells_[column];
    if (cell == CellState::kFree) cell = CellState::kUnknown;
  }
  // Columns seen only as unknown (log-odds exactly at the threshold) are not kept.
  std::erase_if(grid.cells_, [](const auto& entry) { return entry.second == CellState::kUnknown; });
  return grid;
}

CellState OccupancyGrid::at(int i, int j) const {
  const auto found = cells_.find({i, j});
  return found == cells_.end() ? CellState::kUnknown : found->second;
}

void OccupancyGrid::set(int i, int j, CellState state) {
  if (state == CellState::kUnknown) {
    cells_.erase({i, j});
  } else {
    cells_[{i, j}] = state;
  }
}

std::size_t OccupancyGrid::count(CellState state) const {
  return static_cast<std::size_t>(
      std::count_if(cells_.begin(), cells_.end(), [&](const auto& entry) { return entry.second == state; }));
}

void OccupancyGrid::write_map_server(const std::filesystem::path& stem) const {
  int min_i = 0, max_i = 0, min_j = 0, max_j = 0;
  if (!cells_.empty()) {
    min_i = max_i = cells_.begin()->first.first;
    min_j = max_j = cells_.begin()->first.second;
    for (const auto& [index, state] : cells_) {
      min_i = std::min(min_i, index.first);
      max_i = std::max(max_i, index.first);
      min_j = std::min(min_j, index.second);
      max_j = std::max(max_j, index.second);
    }
  }
  const int width = max_i - min_i + 1;
  const int height = max_j - min_j + 1;
  std::string pgm = "P5\n# heslam-occupancy\n" + std::to_string(width) + " " + std::to_string(height) + "\n255\n";
  const std::size_t header = pgm.size();
  pgm.resize(header + static_cast<std::size_t>(width) * height, static_cast<char>(kUnknownValue));
  for (const auto& [index, state] : cells_) {
    const std::size_t row = static_cast<std::size_t>(max_j - index.second);
    const std::size_t col = static_cast<std::size_t>(index.first - min_i);
    pgm[header + row * width + col] = static_cast<char>(state == CellState::kOccupied ? kOccupiedValue : kFreeValue);
  }
  std::filesystem::path pgm_file = stem;
  pgm_file += ".pgm";
  std::filesystem::path yaml_file = stem;
  yaml_file += ".yaml";
  std::ostringstream yaml;
  yaml.precision(12);  // origins are multiples of the resolution: 12 digits print them exactly
  yaml << "image: " << pgm_file.filename().string() << "\n"
       << "mode: trinary\n"
       << "resolution: " << resolution_m_ << "\n"
       << "origin: [" << min_i * resolution_m_ << ", " << min_j * resolution_m_ << ", 0.0]\n"
       << "negate: 0\n"
       << "occupied_thresh: " << kOccupiedThresh << "\n"
       << "free_thresh: " << kFreeThresh << "\n";
  runtime::replace_file_contents(pgm_file, pgm, /*sync=*/false);
  runtime::replace_file_contents(yaml_file, yaml.str(), /*sync=*/false);
}

OccupancyGrid OccupancyGrid::read_map_server(const std::filesystem::path& yaml_file) {
  const std::string source = yaml_file.string();
  // map_server's files are flat "key: value" lines (origin a flow list): read them as such, without
  // cv::FileStorage, which wants its own %YAML:1.0 header that map_server's yaml-cpp refuses.
  std::ifstream yaml(yaml_file);
  if (!yaml) throw std::runtime_error(source + ": cannot open file");
  std::map<std::string, std::string> fields;
  for (std::string line; std::getline(yaml, line);) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    auto trim = [](std::string text) {
      const auto first = text.find_first_not_of(" \t\r\"'");
      const auto last = text.find_last_not_of(" \t\r\"'");
      return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
    };
    fields[trim(line.substr(0, colon))] = trim(line.substr(colon + 1));
  }
  auto number = [&](const std::string& key, const std::string& value) {
    try {
      std::size_t used = 0;
      const double parsed = std::stod(value, &used);
      if (used != value.size()) throw std::invalid_argument(value);
      return parsed;
    } catch (const std::exception&) {
      throw std::runtime_error(source + ": " + key + ": '" + value + "' is not a number");
    }
  };
  auto required = [&](const std::string& key, const std::string& what) {
    const auto found = fields.find(key);
    if (found == fields.end() || found->second.empty())
      throw std::runtime_error(source + ": " + key + ": missing (" + what + ")");
    return found->second;
  };
  const std::string image = required("image", "a file name");
  const double res = number("resolution", required("resolution", "metres"));
  std::string origin_text = required("origin", "[x, y, yaw]");
  if (origin_text.front() != '[' || origin_text.back() != ']') {
    throw std::runtime_error(source + ": origin: expected [x, y, yaw]");
  }
  origin_text = origin_text.substr(1, origin_text.size() - 2);
  std::vector<double> origin;
  std::stringstream origin_items(origin_text);
  for (std::string item; std::getline(origin_items, item, ',');) {
    const auto first = item.find_first_not_of(' ');
    const auto last = item.find_last_not_of(' ');
    if (first == std::string::npos) continue;
    origin.push_back(number("origin", item.substr(first, last - first + 1)));
  }
  if (origin.size() < 2) throw std::runtime_error(source + ": origin: expected [x, y, yaw]");
  if (!(res > 0.0)) throw std::runtime_error(source + ": resolution: must be > 0");
  const bool negate = fields.count("negate") && number("negate", fields["negate"]) != 0.0;
  const double origin_x = origin[0];
  const double origin_y = origin[1];
  const double i0 = origin_x / res;
  const double j0 = origin_y / res;
  if (std::abs(i0 - std::round(i0)) > 1e-6 || std::abs(j0 - std::round(j0)) > 1e-6) {
    throw std::runtime_error(source + ": origin: not on the resolution's lattice (a multiple of resolution)");
  }
  std::filesystem::path pgm_file = std::filesystem::path(image);
  if (pgm_file.is_relative()) pgm_file = yaml_file.parent_path() / pgm_file;
  std::ifstream in(pgm_file, std::ios::binary);
  std::string magic;
  int width = 0, height = 0, max_value = 0;
  in >> magic;
  auto skip_comments = [&] {
    in >> std::ws;
    while (in.peek() == '#') {
      std::string line;
      std::getline(in, line);
      in >> std::ws;
    }
  };
  skip_comments();
  in >> width;
  skip_comments();
  in >> height;
  skip_comments();
  in >> max_value;
  in.get();
  if (!in || magic != "P5" || width <= 0 || height <= 0 || max_value != 255) {
    throw std::runtime_error(pgm_file.string() + ": not an 8-bit binary PGM (P5, maxval 255)");
  }
  std::string pixels(static_cast<std::size_t>(width) * height, '\0');
  in.read(pixels.data(), static_cast<std::streamsize>(pixels.size()));
  if (in.gcount() != static_cast<std::streamsize>(pixels.size())) {
    throw std::runtime_error(pgm_file.string() + ": truncated (" + std::to_string(in.gcount()) + " of " +
                             std::to_string(pixels.size()) + " pixel bytes)");
  }
  const double occupied =
      fields.count("occupied_thresh") ? number("occupied_thresh", fields["occupied_thresh"]) : kOccupiedThresh;
  const double free = fields.count("free_thresh") ? number("free_thresh", fields["free_thresh"]) : kFreeThresh;
  OccupancyGrid grid(res);
  const int min_i = static_cast<int>(std::lround(i0));
  const int min_j = static_cast<int>(std::lround(j0));
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const auto value = static_cast<std::uint8_t>(pixels[static_cast<std::size_t>(row) * width + col]);
      const double p = negate ? value / 255.0 : (255.0 - value) / 255.0;
      const int i = min_i + col;
      const int j = min_j + (height - 1 - row);
      if (p > occupied) {
        grid.set(i, j, CellState::kOccupied);
      } else if (p < free) {
        grid.set(i, j, CellState::kFree);
      }
    }
  }
  return grid;
}

GridAgreement compare(const OccupancyGrid& grid, const OccupancyGrid& truth) {
  if (std::abs(grid.resolution_m() - truth.resolution_m()) > 1e-9) {
    throw std::invalid_argument("compare: grids of different resolutions (" + std::to_string(grid.resolution_m()) +
                                " and " + std::to_string(truth.resolution_m()) + " m)");
  }
  GridAgreement a;
  for (const auto& [index, state] : truth.cells()) {
    if (state != CellState::kOccupied) continue;
    ++a.truth_occupied;
    const CellState seen = grid.at(index.first, index.second);
    if (seen == CellState::kOccupied) ++a.both_occupied;
    if (seen == CellState::kFree) ++a.free_in_truth_occupied;
    if (seen == CellState::kUnknown) ++a.truth_occupied_unknown;
  }
  a.grid_occupied = grid.count(CellState::kOccupied);
  // The Chebyshev distance (1, 2, 3 = three or more) from a cell of one grid to the nearest occupied one of the other.
  const auto distance_bin = [](const OccupancyGrid& other, const std::pair<int, int>& index) {
    for (int radius = 1; radius <= 2; ++radius) {
      for (int di = -radius; di <= radius; ++di) {
        for (int dj = -radius; dj <= radius; ++dj) {
          if (std::max(std::abs(di), std::abs(dj)) != radius) continue;
          if (other.at(index.first + di, index.second + dj) == CellState::kOccupied) return radius - 1;
        }
      }
    }
    return 2;
  };
  for (const auto& [index, state] : grid.cells()) {
    if (state == CellState::kOccupied && truth.at(index.first, index.second) != CellState::kOccupied) {
      ++a.extra_at[distance_bin(truth, index)];
    }
  }
  for (const auto& [index, state] : truth.cells()) {
    if (state == CellState::kOccupied && grid.at(index.first, index.second) != CellState::kOccupied) {
      ++a.missed_at[distance_bin(grid, index)];
    }
  }
  const std::size_t either = a.truth_occupied + a.grid_occupied - a.both_occupied;
  a.occupied_iou = either == 0 ? 1.0 : static_cast<double>(a.both_occupied) / static_cast<double>(either);
  return a;
}

}  // namespace heslam
