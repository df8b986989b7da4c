// Recording the 2D view (see video_sink.hpp).
#include "tools/viewer/video_sink.hpp"

#include <cstdio>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace heslam::viewer {

void VideoSink::write(const cv::Mat& frame_bgr) {
  if (!opened_) {
    opened_ = true;
    size_ = frame_bgr.size();
    if (file_.has_parent_path()) std::filesystem::create_directories(file_.parent_path());
    png_sequence_ = !writer_.open(file_.string(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), fps_, size_, true);
  }
  cv::Mat frame = frame_bgr;
  if (frame.size() != size_) cv::resize(frame_bgr, frame, size_);
  if (!png_sequence_) {
    writer_.write(frame);
  } else {
    char index[16];
    std::snprintf(index, sizeof(index), "_%06llu.png", static_cast<unsigned long long>(frames_));
    const std::filesystem::path png = file_.parent_path() / (file_.stem().string() + index);
    if (!cv::imwrite(png.string(), frame)) throw std::runtime_error("--record: cannot write " + png.string());
  }
  ++frames_;
}

std::string VideoSink::close() {
  if (!opened_) return "--record " + file_.string() + ": no frame to record";
  if (!png_sequence_) {
    writer_.release();
    return "recorded " + std::to_string(frames_) + " frames to " + file_.string();
  }
  return "no video codec could write " + file_.string() + ": recorded " + std::to_string(frames_) + " frames as " +
         (file_.parent_path() / (file_.stem().string() + "_NNNNNN.png")).string();
}

}  // namespace heslam::viewer
