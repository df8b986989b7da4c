// heslam-occupancy-compare: a grid (map_server files) against a ground truth of the same lattice,
// e.g. heslam-synth --occupancy-gt: IoU of occupied cells and the free cells inside walls. Exits 1
// when the grid misses --min-iou or has more than --max-free-in-walls free cells inside walls.
#include <cstdio>
#include <iostream>
#include <limits>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/occupancy/occupancy_grid.hpp"
#include "runtime/flags.hpp"

namespace {

// A top view of a heslam-occupancy PLY (binary x y z float) in the grid frame of up = -y (x, z),
// one pixel per `cell_m`, coloured by height (-y).
void draw_top_view(const std::filesystem::path& ply, const std::filesystem::path& png, double cell_m) {
  std::ifstream in(ply, std::ios::binary);
  if (!in) throw std::runtime_error(ply.string() + ": cannot open");
  std::size_t count = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("element vertex ", 0) == 0) count = std::stoul(line.substr(15));
    if (line == "end_header") break;
  }
  std::vector<float> xyz(count * 3);
  in.read(reinterpret_cast<char*>(xyz.data()), static_cast<std::streamsize>(xyz.size() * sizeof(float)));
  if (!in || count == 0) throw std::runtime_error(ply.string() + ": no points or truncated");
  float min_a = xyz[0], max_a = xyz[0], min_b = xyz[2], max_b = xyz[2], min_h = -xyz[1], max_h = -xyz[1];
  for (std::size_t k = 0; k < count; ++k) {
    min_a = std::min(min_a, xyz[3 * k]);
    max_a = std::max(max_a, xyz[3 * k]);
    min_b = std::min(min_b, xyz[3 * k + 2]);
    max_b = std::max(max_b, xyz[3 * k + 2]);
    min_h = std::min(min_h, -xyz[3 * k + 1]);
    max_h = std::max(max_h, -xyz[3 * k + 1]);
  }
  const int width = static_cast<int>((max_a - min_a) / cell_m) + 1;
  const int height = static_cast<int>((max_b - min_b) / cell_m) + 1;
  cv::Mat heights(height, width, CV_32F, cv::Scalar(-1e9));
  for (std::size_t k = 0; k < count; ++k) {
    const int col = static_cast<int>((xyz[3 * k] - min_a) / cell_m);
    const int row = height - 1 - static_cast<int>((xyz[3 * k + 2] - min_b) / cell_m);
    float& h = heights.at<float>(row, col);
    h = std::max(h, -xyz[3 * k + 1]);
  }
  cv::Mat grey(height, width, CV_8U, cv::Scalar(0));
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const float h = heights.at<float>(r, c);
      if (h > -1e8f)
        grey.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(1 + 254 * (h - min_h) / (max_h - min_h + 1e-6f));
    }
  }
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_VIRIDIS);
  colour.setTo(cv::Scalar(255, 255, 255), grey == 0);
  if (!cv::imwrite(png.string(), colour)) throw std::runtime_error(png.string() + ": cannot write");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam;
  try {
    std::filesystem::path grid_file, truth_file;
    double min_iou = 0.0;
    int max_free_in_walls = std::numeric_limits<int>::max();
    bool help = false;
    std::filesystem::path png, ply, top_png;
    double top_cell_m = 0.02;
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
        .path("--ply", "FILE", &ply, "with --top-png: a heslam-occupancy cloud to draw from above (up = -y)")
        .path("--top-png", "FILE", &top_png, "the cloud's top view, coloured by height")
        .number("--top-cell", "M", &top_cell_m, 0.001, 1.0, "metres per pixel of the top view (0.02)")
        .toggle("--help", &help, "this help");
    flags.parse(argc, argv);
    if (help) {
      std::cout << flags.usage();
      return 0;
    }
    if (!ply.empty() && !top_png.empty()) draw_top_view(ply, top_png, top_cell_m);
    if (grid_file.empty()) return 0;
    const OccupancyGrid grid = OccupancyGrid::read_map_server(grid_file);
    // Without --truth: the grid drawn alone (an empty truth).
    const OccupancyGrid truth =
        truth_file.empty() ? OccupancyGrid(grid.resolution_m()) : OccupancyGrid::read_map_server(truth_file);
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
    std::printf(
        "grid-occupied outside the truth at 1 / 2 / 3+ cells from it: %zu / %zu / %zu; "
        "truth-occupied missed at 1 / 2 / 3+ cells from the grid's: %zu / %zu / %zu\n",
        a.extra_at[0], a.extra_at[1], a.extra_at[2], a.missed_at[0], a.missed_at[1], a.missed_at[2]);
    const bool ok =
        a.occupied_iou >= min_iou && a.free_in_truth_occupied <= static_cast<std::size_t>(max_free_in_walls);
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "heslam-occupancy-compare: " << e.what() << "\n";
    return 2;
  }
}
