// --record FILE: the 2D view as a video through OpenCV's VideoWriter (mp4v), or, when no codec can
// write FILE, as a PNG sequence FILE-stem_000000.png ... in FILE's folder (said once on the log).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

namespace heslam::viewer {

class VideoSink {
 public:
  VideoSink(std::filesystem::path file, double fps) : file_(std::move(file)), fps_(fps) {}
  // The first frame fixes the size; later frames of another size are resized to it. Throws
  // std::runtime_error naming the file when neither the video nor a PNG can be written.
  void write(const cv::Mat& frame_bgr);
  // Closes the video; returns one line describing what was written.
  std::string close();

 private:
  std::filesystem::path file_;
  double fps_;
  cv::VideoWriter writer_;
  bool opened_ = false;
  bool png_sequence_ = false;
  cv::Size size_;
  std::uint64_t frames_ = 0;
};

}  // namespace heslam::viewer
