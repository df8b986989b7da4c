// heslam-occupancy-compare: a grid (map_server files) against a ground truth of the same lattice,
// e.g. heslam-synth --occupancy-gt: IoU of occupied cells and the free cells inside walls. Exits 1
// when the grid misses --min-iou or has more than --max-free-in-walls free cells inside walls.
#include <cstdio>
#include <iostream>
#include <limits>

#include <algorithm>

#include <opencv2/imgcodecs.hpp>

#include "components/core/occupancy/occupancy_grid.hpp"
#include "runtime/flags.hpp"

int main(int argc, char** argv) {
  using namespace heslam;
  try {
    std::filesystem::path grid_file, truth_file;
    double min_iou = 0.0;
    int max_free_in_walls = std::numeric_limits<int>::max();
    bool help = false;
    std::filesystem::path png;
    runtime::Flags flags(
        "heslam-occupancy-compare --grid STEM.yaml --truth GT.yaml [--min-iou X] [--max-free-in-walls N]");
    flags.path("--grid", "FILE", &grid_file, "the grid (map_server YAML)")
        .path("--truth", "FILE", &truth_file, "the ground truth (map_server YAML, same resolution and lattice)")
        .number("--min-iou", "X", &min_iou, 0.0, 1.0, "exit 1 below this IoU of occupied cells (0)")
        .integer("--max-free-in-walls", "N", &max_free_in_walls, 0, std::numeric_limits<int>::max(),
                 "exit 1 with more free cells inside walls (no limit)")
        .path("--png", "FILE", &png,
              "the two drawn over each other: grid occupied black, free white, unknown grey; truth\n"
              "occupied cells the grid has occupied green, free red, unknown blue")
        .toggle("--help", &help, "this help");
    flags.parse(argc, argv);
    if (help) {
      std::cout << flags.usage();
      return 0;
    }
    if (grid_file.empty() || truth_file.empty()) throw std::runtime_error("--grid and --truth are required");
    const OccupancyGrid grid = OccupancyGrid::read_map_server(grid_file);
    const OccupancyGrid truth = OccupancyGrid::read_map_server(truth_file);
    const GridAgreement a = compare(grid, truth);
    if (!png.empty()) {
      int min_i = 0, max_i = 0, min_j = 0, max_j = 0;
      bool first = true;
      for (const OccupancyGrid* g : {&grid, &truth}) {
        for (const auto& [index, state] : g->cells()) {
          min_i = first ? index.first : std::min(min_i, index.first);
          max_i = first ? index.first : std::max(max_i, index.first);
          min_j = first ? index.second : std::min(min_j, index.second);
          max_j = first ? index.second : std::max(max_j, index.second);
          first = false;
        }
      }
      cv::Mat image(max_j - min_j + 1, max_i - min_i + 1, CV_8UC3, cv::Scalar(128, 128, 128));
      auto pixel = [&](int i, int j) -> cv::Vec3b& { return image.at<cv::Vec3b>(max_j - j, i - min_i); };
      for (const auto& [index, state] : grid.cells()) {
        pixel(index.first, index.second) =
            state == CellState::kOccupied ? cv::Vec3b(0, 0, 0) : cv::Vec3b(255, 255, 255);
      }
      for (const auto& [index, state] : truth.cells()) {
        if (state != CellState::kOccupied) continue;
        const CellState seen = grid.at(index.first, index.second);
        pixel(index.first, index.second) = seen == CellState::kOccupied ? cv::Vec3b(0, 160, 0)
                                           : seen == CellState::kFree   ? cv::Vec3b(0, 0, 255)
                                                                        : cv::Vec3b(255, 0, 0);
      }
      if (!cv::imwrite(png.string(), image)) throw std::runtime_error(png.string() + ": cannot write");
    }
    std::printf(
        "occupied IoU %.4f (%zu of %zu truth cells, %zu grid cells), truth-occupied cells free %zu, unknown %zu\n",
        a.occupied_iou, a.both_occupied, a.truth_occupied, a.grid_occupied, a.free_in_truth_occupied,
        a.truth_occupied_unknown);
    const bool ok =
        a.occupied_iou >= min_iou && a.free_in_truth_occupied <= static_cast<std::size_t>(max_free_in_walls);
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "heslam-occupancy-compare: " << e.what() << "\n";
    return 2;
  }
}
