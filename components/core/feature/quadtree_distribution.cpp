// Quadtree distribution of keypoints (ORB-SLAM2's DistributeOctTree, with deterministic ordering).
#include "components/core/feature/quadtree_distribution.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace heslam {
namespace {

// A cell owns the range [begin, end) of the shared index array; splitting a cell only permutes its
// own range, so no cell allocates.
struct Cell {
  float x0, x1, y0, y1;
  int begin, end;
  int size() const { return end - begin; }
  bool splittable() const { return end - begin > 1; }
};

// Four quadrants of `cell`, in the order top-left, top-right, bottom-left, bottom-right; empty ones
// are dropped.
void split(const Cell& cell, std::span<const ScoredPoint> points, std::vector<int>& index, std::vector<Cell>& out) {
  const float half_x = std::ceil((cell.x1 - cell.x0) * 0.5f);
  const float half_y = std::ceil((cell.y1 - cell.y0) * 0.5f);
  const float mid_x = cell.x0 + half_x;
  const float mid_y = cell.y0 + half_y;
  auto at = [&](int i) -> const ScoredPoint& { return points[static_cast<std::size_t>(i)]; };
  const auto first = index.begin() + cell.begin;
  const auto last = index.begin() + cell.end;
  const auto bottom = std::partition(first, last, [&](int i) { return at(i).y < mid_y; });
  const auto top_right = std::partition(first, bottom, [&](int i) { return at(i).x < mid_x; });
  const auto bottom_right = std::partition(bottom, last, [&](int i) { return at(i).x < mid_x; });
  auto offset = [&](std::vector<int>::iterator it) { return static_cast<int>(it - index.begin()); };
  const Cell quadrants[4] = {{cell.x0, mid_x, cell.y0, mid_y, cell.begin, offset(top_right)},
                             {mid_x, cell.x1, cell.y0, mid_y, offset(top_right), offset(bottom)},
                             {cell.x0, mid_x, mid_y, cell.y1, offset(bottom), offset(bottom_right)},
                             {mid_x, cell.x1, mid_y, cell.y1, offset(bottom_right), cell.end}};
  for (const Cell& q : quadrants) {
    if (q.size() > 0) out.push_back(q);
  }
}

}  // namespace

std::vector<int> distribute_quadtree(std::span<const ScoredPoint> points, float min_x, float max_x, float min_y,
                                     float max_y, int wanted) {
  std::vector<int> kept;
  if (points.empty() || wanted <= 0) return kept;
  const float width = max_x - min_x;
  const float height = max_y - min_y;

  // Initial cells: about square, side = image height (ORB-SLAM2: round(width / height) of them).
  const int initial = std::max(1, static_cast<int>(std::lround(width / std::max(height, 1.f))));
  const float initial_w = width / static_cast<float>(initial);
  auto initial_cell = [&](const ScoredPoint& p) {
    return std::clamp(static_cast<int>((p.x - min_x) / initial_w), 0, initial - 1);
  };
  // Points ordered by initial cell, by index within a cell (a counting sort: one pass to count, one
  // to place).
  std::vector<int> cell_of(points.size());
  std::vector<int> start(static_cast<std::size_t>(initial) + 1, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    cell_of[i] = initial_cell(points[i]);
    ++start[static_cast<std::size_t>(cell_of[i]) + 1];
  }
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<int> index(points.size());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    index[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = static_cast<int>(i);
  }
  std::vector<Cell> cells;
  for (int c = 0; c < initial; ++c) {
    const int begin = start[static_cast<std::size_t>(c)];
    const int end = start[static_cast<std::size_t>(c) + 1];
    if (end > begin) cells.push_back({min_x + initial_w * c, min_x + initial_w * (c + 1), min_y, max_y, begin, end});
  }

  const auto wanted_cells = static_cast<std::size_t>(wanted);
  std::vector<Cell> next;
  while (true) {
    // Split every splittable cell once.
    const std::size_t before = cells.size();
    std::size_t splittable_after = 0;
    next.clear();
    for (const Cell& cell : cells) {
      if (cell.splittable()) {
        split(cell, points, index, next);
      } else {
        next.push_back(cell);
      }
    }
    cells.swap(next);
    for (const Cell& c : cells) splittable_after += c.splittable() ? 1 : 0;
    if (cells.size() >= wanted_cells || cells.size() == before) break;

    // Close to the target: a full round would overshoot, so split the most crowded cells first, one
    // by one, and stop as soon as there are enough.
    if (cells.size() + splittable_after * 3 > wanted_cells) {
      while (cells.size() < wanted_cells) {
        const std::size_t round_start = cells.size();
        std::vector<std::size_t> order;
        for (std::size_t i = 0; i < cells.size(); ++i) {
          if (cells[i].splittable()) order.push_back(i);
        }
        if (order.empty()) break;
        std::stable_sort(order.begin(), order.end(),
                         [&](std::size_t a, std::size_t b) { return cells[a].size() > cells[b].size(); });
        std::vector<bool> removed(cells.size(), false);
        std::vector<Cell> children;
        std::size_t count = cells.size();
        for (std::size_t i : order) {
          const std::size_t first_child = children.size();
          split(cells[i], points, index, children);
          removed[i] = true;
          count += children.size() - first_child - 1;
          if (count >= wanted_cells) break;
        }
        next.clear();
        for (std::size_t i = 0; i < cells.size(); ++i) {
          if (!removed[i]) next.push_back(cells[i]);
        }
        next.insert(next.end(), children.begin(), children.end());
        cells.swap(next);
        if (cells.size() == round_start) break;
      }
      break;
    }
  }

  // The strongest point of each cell; ties go to the lower index.
  kept.reserve(cells.size());
  for (const Cell& cell : cells) {
    int best = index[static_cast<std::size_t>(cell.begin)];
    for (int k = cell.begin + 1; k < cell.end; ++k) {
      const int i = index[static_cast<std::size_t>(k)];
      const float r = points[static_cast<std::size_t>(i)].response;
      const float r_best = points[static_cast<std::size_t>(best)].response;
      if (r > r_best || (r == r_best && i < best)) best = i;
    }
    kept.push_back(best);
  }
  return kept;
}

}  // namespace heslam
