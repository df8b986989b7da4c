// Writes the viewer's pictures into --out: numbered snapshots (map_0001.png top view,
// frame_0001.png 2D view, map_3d_0001.png when a 3D window is open), the final ones (*_final.png)
// and viewer_stats.txt, the counts a test or a user checks the pictures against.
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include <opencv2/core.hpp>

namespace heslam::viewer {

class SnapshotWriter {
 public:
  // Creates the folder; throws std::runtime_error naming it when that fails.
  explicit SnapshotWriter(std::filesystem::path dir);
  // `label` is a number ("0001") or "final"; an empty 3D picture is skipped. Throws
  // std::runtime_error naming the file when a PNG cannot be written.
  void write(const std::string& label, const cv::Mat& top_view, const cv::Mat& frame_view, const cv::Mat& view_3d);
  // key=value lines, written atomically (temp file + rename).
  void write_stats(const std::map<std::string, std::string>& stats) const;
  const std::filesystem::path& dir() const { return dir_; }
  int written() const { return written_; }

 private:
  std::filesystem::path dir_;
  int written_ = 0;
};

}  // namespace heslam::viewer
