// Results as JSON for scripts: one object per command with settings, pair counts and statistics.
//
// API:
//   std::string text = to_json(ape_result, JsonContext{.gt_path = ..., .est_path = ...});
//   write_text_file("ape.json", text);     // throws std::runtime_error naming the file on failure
// Numbers are written with 17 significant digits (they round-trip exactly).
#pragma once

#include <filesystem>
#include <string>

#include "tools/eval/ape.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/rpe.hpp"

namespace heslam::eval {

struct JsonContext {
  std::string gt_path;
  std::string est_path;
  std::size_t gt_poses = 0;
  std::size_t est_poses = 0;
  bool associated_by_time = false;
  double max_dt_s = 0.0;
};

std::string to_json(const ApeResult& ape, const JsonContext& context);
std::string to_json(const RpeResult& rpe, const JsonContext& context);
std::string to_json(const KittiResult& kitti, const JsonContext& context);

void write_text_file(const std::filesystem::path& path, const std::string& text);

}  // namespace heslam::eval
