// PNG snapshots and the stats file of the viewer (see snapshot_writer.hpp).
#include "tools/viewer/snapshot_writer.hpp"

#include <sstream>
#include <stdexcept>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "runtime/atomic_file.hpp"

namespace heslam::viewer {
namespace {

// Pictures are replaced whole (a reader never sees half of one) but not fsynced: they are written
// again and again while the viewer runs, and losing the last one to a power cut costs nothing.
constexpr bool kSyncWrites = false;

void write_png(const std::filesystem::path& file, const cv::Mat& image) {
  if (image.empty()) return;
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", image, png))
    throw std::runtime_error("cannot write " + file.string() + ": PNG encoding failed");
  runtime::replace_file_contents(file, {reinterpret_cast<const char*>(png.data()), png.size()}, kSyncWrites);
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
  std::ostringstream text;
  for (const auto& [key, value] : stats) text << key << "=" << value << "\n";
  runtime::replace_file_contents(dir_ / "viewer_stats.txt", text.view(), kSyncWrites);
}

}  // namespace heslam::viewer
