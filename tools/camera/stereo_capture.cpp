// Image streams (devices, video files, folders), side-by-side splitting, pairing and the input checks.
#include "tools/camera/stereo_capture.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "tools/dataset/dataset_readers.hpp"

namespace heslam {

namespace fs = std::filesystem;

namespace {

constexpr double kNsPerMs = 1e6;
constexpr double kNsPerS = 1e9;
// A folder's images: the extensions cv::imread reads that cameras and datasets use.
constexpr const char* kImageExtensions[] = {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".bmp", ".tif", ".tiff"};

std::int64_t steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string size_text(const cv::Size& size) { return std::to_string(size.width) + "x" + std::to_string(size.height); }

bool all_digits(const std::string& text) {
  return !text.empty() && std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c); });
}

// A V4L2 device or a video file through cv::VideoCapture.
class VideoStream final : public ImageStream {
 public:
  VideoStream(const std::string& source, bool device, const StreamOptions& options) : source_(source), device_(device) {
    if (device_) {
      const bool opened =
          all_digits(source) ? capture_.open(std::stoi(source), cv::CAP_V4L2) : capture_.open(source, cv::CAP_V4L2);
      if (!opened) {
        throw std::runtime_error(
            "camera " + source + ": cannot open the V4L2 device (" +
            (all_digits(source) || fs::exists(source) ? "busy, or not a capture device" : "no such device") + ")");
      }
      if (options.device_size.area() > 0) {
        capture_.set(cv::CAP_PROP_FRAME_WIDTH, options.device_size.width);
        capture_.set(cv::CAP_PROP_FRAME_HEIGHT, options.device_size.height);
      }
      if (options.fps > 0) capture_.set(cv::CAP_PROP_FPS, options.fps);
    } else {
      if (!capture_.open(source, cv::CAP_FFMPEG) && !capture_.open(source)) {
        throw std::runtime_error(source + ": cannot open as a video file (no OpenCV backend decodes it)");
      }
      fps_ = capture_.get(cv::CAP_PROP_FPS);
      const double count = capture_.get(cv::CAP_PROP_FRAME_COUNT);
      frame_count_ = count > 0 ? static_cast<std::size_t>(count) : 0;
    }
  }

  std::optional<StreamImage> next() override {
    StreamImage image;
    if (!capture_.read(image.image) || image.image.empty()) {
      ended_ = true;
      return std::nullopt;
    }
    const double position_ms = capture_.get(cv::CAP_PROP_POS_MSEC);
    if (device_) {
      // V4L2 reports the driver's buffer time (CLOCK_MONOTONIC, as the steady clock); 0 when it has none.
      driver_stamps_ = position_ms > 0;
      image.time_ns = driver_stamps_ ? std::llround(position_ms * kNsPerMs) : steady_now_ns();
    } else if (read_ > 0 && position_ms <= 0 && fps_ > 0) {
      image.time_ns = std::llround(static_cast<double>(read_) * kNsPerS / fps_);  // no presentation times
    } else {
      image.time_ns = std::llround(position_ms * kNsPerMs);
    }
    ++read_;
    return image;
  }

  bool live() const override { return device_; }
  bool stamped() const override { return device_; }
  std::string name() const override { return device_ ? "camera " + source_ : source_; }
  std::string end_reason() const override {
    return device_ ? "camera " + source_ + " stopped delivering frames after " + std::to_string(read_) +
                         " (unplugged, or the driver failed)"
                   : "end of " + source_ + " after " + std::to_string(read_) + " frames";
  }
  std::size_t frame_count() const override { return frame_count_; }

 private:
  std::string source_;
  bool device_;
  cv::VideoCapture capture_;
  double fps_ = 0.0;
  std::size_t frame_count_ = 0;
  std::size_t read_ = 0;
  bool ended_ = false;
  bool driver_stamps_ = false;
};

struct FolderEntry {
  fs::path file;
  std::int64_t time_ns = 0;
};

std::vector<FolderEntry> list_images(const fs::path& folder, double fps) {
  const fs::path images = fs::is_directory(folder / "data") ? folder / "data" : folder;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(images)) {
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (entry.is_regular_file() &&
        std::find(std::begin(kImageExtensions), std::end(kImageExtensions), extension) != std::end(kImageExtensions)) {
      files.push_back(entry.path());
    }
  }
  if (files.empty()) throw std::runtime_error(images.string() + ": no images (png, jpg, pgm, ...) and no data.csv");
  if (!(fps > 0)) {
    throw std::runtime_error(folder.string() +
                             ": a folder without data.csv has no stamps: give its rate with --fps (or a calibration "
                             "with a rate, e.g. EuRoC sensor.yaml rate_hz)");
  }
  std::sort(files.begin(), files.end());
  std::vector<FolderEntry> entries;
  for (std::size_t i = 0; i < files.size(); ++i) {
    entries.push_back({files[i], std::llround(static_cast<double>(i) * kNsPerS / fps)});
  }
  return entries;
}

class FolderStream final : public ImageStream {
 public:
  FolderStream(const fs::path& folder, const StreamOptions& options, Warn warn)
      : folder_(folder), warn_(std::move(warn)) {
    stamped_ = fs::exists(folder / "data.csv");
    if (stamped_) {
      // The EuRoC frame list in file order, as a driver delivered the frames (backwards stamps are counted).
      for (const dataset_detail::CsvRow& row :
           dataset_detail::read_camera_csv(folder, dataset_detail::StampOrder::kAsListed)) {
        entries_.push_back({row.image, row.stamp_ns});
      }
    } else {
      entries_ = list_images(folder, options.fps);
    }
  }

  std::optional<StreamImage> next() override {
    while (index_ < entries_.size()) {
      const FolderEntry& entry = entries_[index_++];
      try {
        return StreamImage{load_image_file(entry.file), entry.time_ns};
      } catch (const std::exception& error) {
        ++unreadable_;
        warn_("unreadable", std::string("skipped image: ") + error.what());
      }
    }
    return std::nullopt;
  }

  bool live() const override { return false; }
  bool stamped() const override { return stamped_; }
  std::string name() const override { return folder_.string(); }
  std::string end_reason() const override {
    return "end of " + folder_.string() + " after " + std::to_string(index_) + " images";
  }
  std::size_t frame_count() const override { return entries_.size(); }
  std::size_t unreadable() const override { return unreadable_; }

 private:
  fs::path folder_;
  Warn warn_;
  std::vector<FolderEntry> entries_;
  std::size_t index_ = 0;
  std::size_t unreadable_ = 0;
  bool stamped_ = false;
};

std::vector<std::string> split_sources(const std::string& source) {
  std::vector<std::string> parts;
  std::stringstream in(source);
  for (std::string part; std::getline(in, part, ',');) parts.push_back(part);
  if (!source.empty() && source.back() == ',') parts.push_back("");
  return parts;
}

}  // namespace

const char* to_string(CameraLayout layout) {
  switch (layout) {
    case CameraLayout::kAuto: return "auto";
    case CameraLayout::kTwoDevices: return "two-devices";
    case CameraLayout::kSideBySide: return "side-by-side";
  }
  return "?";
}

std::unique_ptr<ImageStream> open_stream(const std::string& source, const StreamOptions& options, Warn warn) {
  if (source.empty()) throw std::runtime_error("empty source (expected a device, a video file or an image folder)");
  if (source.rfind("/dev/", 0) == 0 || all_digits(source)) {
    return std::make_unique<VideoStream>(source, /*device=*/true, options);
  }
  if (fs::is_directory(source)) return std::make_unique<FolderStream>(source, options, std::move(warn));
  if (fs::is_regular_file(source)) return std::make_unique<VideoStream>(source, /*device=*/false, options);
  throw std::runtime_error(source + ": no such device, video file or image folder");
}

SourceStreams open_source(const std::string& source, CameraLayout layout, const StreamOptions& options, Warn warn) {
  const std::vector<std::string> parts = split_sources(source);
  const fs::path mav0 = parts.size() == 1 ? dataset_detail::find_euroc_mav0(parts[0]) : fs::path{};
  SourceStreams result;
  result.layout = layout != CameraLayout::kAuto          ? layout
                  : (parts.size() == 2 || !mav0.empty()) ? CameraLayout::kTwoDevices
                                                         : CameraLayout::kSideBySide;
  if (parts.size() > 2) throw std::runtime_error("source '" + source + "': at most two sources (LEFT,RIGHT)");
  if (result.layout == CameraLayout::kSideBySide) {
    if (parts.size() != 1) {
      throw std::runtime_error("source '" + source +
                               "': side-by-side takes one source, got two (LEFT,RIGHT is for "
                               "--layout two-devices)");
    }
    result.streams.push_back(open_stream(parts[0], options, warn));
    return result;
  }
  if (parts.size() == 2) {
    result.streams.push_back(open_stream(parts[0], options, warn));
    result.streams.push_back(open_stream(parts[1], options, warn));
  } else if (!mav0.empty()) {
    result.streams.push_back(open_stream((mav0 / "cam0").string(), options, warn));
    result.streams.push_back(open_stream((mav0 / "cam1").string(), options, warn));
  } else {
    throw std::runtime_error("source '" + source +
                             "': two-devices needs LEFT,RIGHT (two devices, files or folders) or an EuRoC folder "
                             "with cam0/ and cam1/");
  }
  if (result.streams[0]->live() != result.streams[1]->live()) {
    throw std::runtime_error("source '" + source + "': left and right must both be devices, or both recordings");
  }
  return result;
}

StereoCapture::StereoCapture(SourceStreams source, const CaptureOptions& options, Warn warn)
    : layout_(source.layout), streams_(std::move(source.streams)), options_(options), warn_(std::move(warn)) {}

bool StereoCapture::live() const { return streams_.front()->live(); }

std::string StereoCapture::describe() const {
  std::string text = std::string(to_string(layout_)) + " from " + streams_[0]->name();
  if (streams_.size() == 2) text += " and " + streams_[1]->name();
  return text;
}

std::string StereoCapture::end_reason() const {
  // With two sources the pairing stops at the first that ends: that one is named.
  return ended_ ? ended_->end_reason() : streams_.front()->end_reason();
}

std::size_t StereoCapture::frame_count() const {
  std::size_t count = streams_[0]->frame_count();
  if (streams_.size() == 2) count = std::min(count, streams_[1]->frame_count());
  return count;
}

std::optional<StreamImage> StereoCapture::read(ImageStream& stream) {
  const std::size_t unreadable_before = stream.unreadable();
  std::optional<StreamImage> image = stream.next();
  counts_.unreadable += stream.unreadable() - unreadable_before;
  if (!image && !ended_) ended_ = &stream;
  if (image) {
    image->image = to_mono8(image->image, stream);
    image->time_ns = stamp_of(stream, image->time_ns);
  }
  return image;
}

cv::Mat StereoCapture::to_mono8(const cv::Mat& image, const ImageStream& stream) {
  if (image.depth() != CV_8U) {
    throw std::runtime_error(stream.name() + ": images are not 8-bit (OpenCV depth " + std::to_string(image.depth()) +
                             "); heslam takes 8-bit mono or colour");
  }
  if (image.channels() == 1) return image;
  if (image.channels() != 3 && image.channels() != 4) {
    throw std::runtime_error(stream.name() + ": images with " + std::to_string(image.channels()) +
                             " channels (expected 1, 3 or 4)");
  }
  if (!said_converted_) {
    said_converted_ = true;
    warn_("converted", stream.name() + " delivers " + std::to_string(image.channels()) +
                           "-channel images: converted to mono8 (grey) before publishing");
  }
  cv::Mat gray;
  cv::cvtColor(image, gray, image.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  return gray;
}

std::int64_t StereoCapture::stamp_of(const ImageStream& stream, std::int64_t time_ns) {
  if (stream.stamped()) return time_ns;
  // Both streams of a pair of files share one base, so their presentation times pair.
  if (!stamp_base_ns_)
    stamp_base_ns_ = (options_.first_stamp_ns > 0 ? options_.first_stamp_ns : steady_now_ns()) - time_ns;
  return *stamp_base_ns_ + time_ns;
}

void StereoCapture::check_size(const cv::Mat& image, const ImageStream& stream) const {
  if (image.size() == options_.calibrated_size) return;
  throw std::runtime_error("wrong resolution: " + stream.name() + " delivers " + size_text(image.size()) + " images" +
                           (layout_ == CameraLayout::kSideBySide ? " per camera (each half)" : "") +
                           ", the calibration " + options_.calibration_source + " is for " +
                           size_text(options_.calibrated_size));
}

std::optional<CapturedFrame> StereoCapture::next() {
  for (;;) {
    CapturedFrame frame;
    if (layout_ == CameraLayout::kSideBySide) {
      std::optional<StreamImage> image = read(*streams_[0]);
      if (!image) return std::nullopt;
      const int width = image->image.cols;
      if (width % 2 != 0) {
        throw std::runtime_error(streams_[0]->name() + ": side-by-side frame is " + std::to_string(width) +
                                 " px wide (odd): it cannot be two images of one size");
      }
      frame.images.left = image->image.colRange(0, width / 2).clone();
      frame.images.right = image->image.colRange(width / 2, width).clone();
      frame.stamp_ns = frame.right_stamp_ns = image->time_ns;
    } else {
      const std::function<std::optional<StreamImage>()> left = [this] { return read(*streams_[0]); };
      const std::function<std::optional<StreamImage>()> right = [this] { return read(*streams_[1]); };
      const std::function<std::int64_t(const StreamImage&)> stamp = [](const StreamImage& i) { return i.time_ns; };
      auto pair = next_stereo_pair<StreamImage>(left, right, stamp, options_.pair_tolerance_ns, counts_.pairing);
      if (!pair) return std::nullopt;
      frame.images.left = std::move(pair->first.image);
      frame.images.right = std::move(pair->second.image);
      frame.stamp_ns = pair->first.time_ns;
      frame.right_stamp_ns = pair->second.time_ns;
      if (!frame.images.left.isContinuous()) frame.images.left = frame.images.left.clone();
      if (!frame.images.right.isContinuous()) frame.images.right = frame.images.right.clone();
    }
    check_size(frame.images.left, *streams_[0]);
    check_size(frame.images.right, *streams_.back());
    frame.images.encoding = "mono8";
    frame.source_time_ns = frame.stamp_ns;
    if (last_stamp_ns_ && frame.stamp_ns <= *last_stamp_ns_) {
      ++counts_.stamps_backwards;
      warn_("backwards", "stamps going backwards: frame stamped " + std::to_string(frame.stamp_ns) + " ns after " +
                             std::to_string(*last_stamp_ns_) + " ns; skipped");
      continue;
    }
    last_stamp_ns_ = frame.stamp_ns;
    ++counts_.frames;
    return frame;
  }
}

}  // namespace heslam
