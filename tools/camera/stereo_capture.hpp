// Where heslam-camera's images come from, DDS-free: V4L2 devices and video files through OpenCV's
// VideoCapture, image folders (EuRoC cam0/ with data.csv, or plain sorted images), one source of
// side-by-side frames or two sources paired by stamp, checked against the calibration.
//
//   StereoCapture capture(open_streams(spec), options, warn);
//   while (std::optional<CapturedFrame> frame = capture.next()) publish(*frame);
//   capture.end_reason();   // "end of file after 160 frames", "... stopped delivering frames"
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "tools/camera/stereo_pairing.hpp"
#include "tools/dataset/stereo_images.hpp"

namespace heslam {

enum class CameraLayout { kAuto, kTwoDevices, kSideBySide };
const char* to_string(CameraLayout layout);

// One image of a stream. time_ns: a driver's or a recording's absolute stamp when the stream is
// stamped(), else the image's time within the source (from 0: video presentation time, index / fps).
struct StreamImage {
  cv::Mat image;
  std::int64_t time_ns = 0;
};

// A warning line; `kind` groups repeats for throttling ("unreadable", "backwards", "converted").
using Warn = std::function<void(const std::string& kind, const std::string& line)>;

class ImageStream {
 public:
  virtual ~ImageStream() = default;
  // The next image; nothing at the end of the source (end_reason() says which end).
  virtual std::optional<StreamImage> next() = 0;
  virtual bool live() const = 0;     // a device: never paced, and its end is a failure
  virtual bool stamped() const = 0;  // times are absolute stamps (driver, data.csv)
  virtual std::string name() const = 0;
  virtual std::string end_reason() const = 0;
  virtual std::size_t frame_count() const { return 0; }  // 0: unknown (a device)
  virtual std::size_t unreadable() const { return 0; }   // images skipped as missing or corrupt
};

struct StreamOptions {
  cv::Size device_size;  // per device: the size asked of a V4L2 device (the calibration's)
  double fps = 0.0;      // plain image folders (required there); devices: the rate asked (0: theirs)
};

// "/dev/videoN" or a number: a V4L2 device; a folder: images; another existing file: a video.
// Throws one line naming the source when it cannot be opened.
std::unique_ptr<ImageStream> open_stream(const std::string& source, const StreamOptions& options, Warn warn);

// The streams SOURCE names for a layout (auto decided here): "LEFT,RIGHT" or an EuRoC folder (cam0/,
// cam1/) for two-devices, one source for side-by-side. Throws on a mismatch, naming both.
struct SourceStreams {
  CameraLayout layout = CameraLayout::kAuto;
  std::vector<std::unique_ptr<ImageStream>> streams;  // 1 (side-by-side) or 2 (left, right)
};
SourceStreams open_source(const std::string& source, CameraLayout layout, const StreamOptions& options, Warn warn);

struct CaptureOptions {
  std::int64_t pair_tolerance_ns = 10'000'000;
  cv::Size calibrated_size;        // each camera's raw size per the calibration
  std::string calibration_source;  // named in the wrong-resolution line
  // Stamp of the first image of an unstamped stream (video file, plain folder); 0: the steady clock
  // when it is captured. Later images: that + their time in the source.
  std::int64_t first_stamp_ns = 0;
};

struct CaptureCounts {
  std::size_t frames = 0;  // pairs delivered by next()
  PairingCounts pairing;
  std::size_t stamps_backwards = 0;  // pairs not after the previous one, skipped
  std::size_t unreadable = 0;        // images of a folder that could not be read, skipped
};

struct CapturedFrame {
  StereoImages images;  // mono8, each the calibrated size, continuous
  std::int64_t stamp_ns = 0;
  std::int64_t right_stamp_ns = 0;
  std::int64_t source_time_ns = 0;  // for pacing a recording at its own rate
};

class StereoCapture {
 public:
  StereoCapture(SourceStreams source, const CaptureOptions& options, Warn warn);

  // The next pair; nothing at the end. Throws std::runtime_error on input the run cannot go on
  // with: a size other than the calibration's, an odd side-by-side width, images not 8-bit.
  std::optional<CapturedFrame> next();

  const CaptureCounts& counts() const { return counts_; }
  CameraLayout layout() const { return layout_; }
  bool live() const;
  std::string describe() const;
  std::string end_reason() const;
  std::size_t frame_count() const;  // pairs the source holds when known, else 0

 private:
  std::optional<StreamImage> read(ImageStream& stream);
  cv::Mat to_mono8(const cv::Mat& image, const ImageStream& stream);
  void check_size(const cv::Mat& image, const ImageStream& stream) const;
  std::int64_t stamp_of(const ImageStream& stream, std::int64_t time_ns);

  CameraLayout layout_;
  std::vector<std::unique_ptr<ImageStream>> streams_;
  CaptureOptions options_;
  Warn warn_;
  CaptureCounts counts_;
  std::optional<std::int64_t> stamp_base_ns_;
  std::optional<std::int64_t> last_stamp_ns_;
  const ImageStream* ended_ = nullptr;  // the stream whose end ended the capture
  bool said_converted_ = false;
};

}  // namespace heslam
