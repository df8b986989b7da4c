// PNG snapshots and the stats file of the viewer (see snapshot_writer.hpp).
#include "tools/viewer/snapshot_writer.hpp"

#include <fstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

namespace heslam::viewer {
namespace {

void write_png(const std::filesystem::path& file, const cv::Mat& image) {
  if (image.empty()) return;
  const std::filesystem::path temp = file.string() + ".tmp.png";
  if (!cv::imwrite(temp.string(), image)) throw std::runtime_error("cannot write " + file.string());
  std::filesystem::rename(temp, file);  // a reader never sees half a picture
}

}  // namespace

SnapshotWriter::SnapshotWriter(std::filesystem::path dir) : dir_(std::move(dir)) {
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  if (error) throw std::runtime_error("--out " + dir_.string() + ": cannot create the folder: " + error.message());
}

void SnapshotWriter::write(const std::string& label, const cv::Mat& top_view, const cv::Mat& frame_view,
                           const cv::Mat& view_3d) {
  write_png(dir_ / ("map_" + label + ".png"), top_view);
  write_png(dir_ / ("frame_" + label + ".png"), frame_view);
  write_png(dir_ / ("map_3d_" + label + ".png"), view_3d);
  ++written_;
}

void SnapshotWriter::write_stats(const std::map<std::string, std::string>& stats) const {
  const std::filesystem::path file = dir_ / "viewer_stats.txt";
  const std::filesystem::path temp = file.string() + ".tmp";
  {
    std::ofstream out(temp);
    for (const auto& [key, value] : stats) out << key << "=" << value << "\n";
    if (!out) throw std::runtime_error("cannot write " + file.string());
  }
  std::filesystem::rename(temp, file);
}

}  // namespace heslam::viewer
