// The camera loop: a capture thread reads, checks and paces pairs into a one-frame slot (a pair that
// replaces one not yet published is a dropped frame); this thread publishes them.
#include "tools/camera/camera.hpp"

#include <time.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <optional>
#include <thread>

#include "components/core/camera/stereo_rectifier.hpp"
#include "runtime/image_transport.hpp"
#include "runtime/participant.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/status.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "tools/camera/camera_calibration.hpp"
#include "tools/camera/latest_slot.hpp"
#include "tools/camera/stereo_capture.hpp"
#include "tools/replay/replay_messages.hpp"
#include "tools/replay/replay_pacer.hpp"

namespace heslam {

namespace {

using Clock = std::chrono::steady_clock;

// The publishing thread wakes this often to notice a stop while no frame comes.
constexpr std::chrono::milliseconds kTakePeriod{50};
// Pacing sleeps in slices of at most this, to notice a stop.
constexpr std::int64_t kPaceSliceNs = 20'000'000;
// At the end, reliable frames still in flight get this long to be acknowledged by readers.
constexpr std::chrono::seconds kFinalAckTimeout{2};

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

double process_cpu_ms() {
  timespec time{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &time);
  return static_cast<double>(time.tv_sec) * 1e3 + static_cast<double>(time.tv_nsec) * 1e-6;
}

CaptureOptions capture_options(const CameraOptions& options, const StereoCalibration& calibration) {
  CaptureOptions capture;
  capture.pair_tolerance_ns = static_cast<std::int64_t>(options.pair_tolerance_ms * 1e6);
  capture.calibrated_size = cv::Size(calibration.left.width_px, calibration.left.height_px);
  capture.calibration_source = calibration.source;
  capture.first_stamp_ns = options.first_stamp_ns;
  return capture;
}

StreamOptions stream_options(const CameraOptions& options, const StereoCalibration& calibration) {
  StreamOptions stream;
  stream.fps = options.fps > 0 ? options.fps : calibration.rate_hz;
  stream.device_size = cv::Size(calibration.left.width_px, calibration.left.height_px);
  return stream;
}

// The calibration, its rectification and the source, as a run and --check open them.
struct Opened {
  StereoCalibration calibration;
  StereoRectifier rectifier;
  StereoCapture capture;

  Opened(const CameraOptions& options, const Warn& warn)
      : calibration(load_camera_calibration(options.calibration)),
        rectifier(calibration),
        capture(open_side(options, calibration, warn), capture_options(options, calibration), warn) {
    if (capture.live() && options.rate != 1.0) {
      throw std::runtime_error("--rate: a camera runs at its own rate (--rate is for video files and folders)");
    }
  }

 private:
  static SourceStreams open_side(const CameraOptions& options, const StereoCalibration& calibration, const Warn& warn) {
    StreamOptions stream = stream_options(options, calibration);
    if (options.layout == CameraLayout::kSideBySide) stream.device_size.width *= 2;
    return open_source(options.source, options.layout, stream, warn);
  }
};

class Camera {
 public:
  Camera(const runtime::CommonArgs& common, const CameraOptions& options)
      : options_(options),
        log_(common.name, common.log_level),
        opened_(options, [this](const std::string& kind, const std::string& line) { warn(kind, line); }),
        calibration_message_(opened_.calibration, opened_.rectifier.camera()),
        participant_({.domain_id = common.domain_id, .dds_config = common.dds_config}),
        image_participant_(participant_, common.image_transport, common.image_domain_id, common.dds_config),
        topics_(common.ns, common.agent_ns),
        status_(participant_, topics_, common.name, stats_),
        calibration_writer_(participant_, topics_.calibration()),
        frame_writer_(image_participant_.get(), topics_.stereo()) {
    if (opened_.capture.frame_count() > 0) stats_.count(runtime::kFramesTotal, opened_.capture.frame_count());
  }

  int run() {
    StereoCapture& capture = opened_.capture;
    log_.info("camera: ", capture.describe(), " (",
              capture.live() ? "live" : "recording, rate " + format(options_.rate), "), calibration ",
              opened_.calibration.source, " (", to_string(detect_calibration_format(options_.calibration)), "), ",
              opened_.calibration.left.width_px, "x", opened_.calibration.left.height_px, " per camera; on domain ",
              participant_.domain_id(), " as '", frame_writer_.name(), "'");
    calibration_writer_.write(calibration_message_.get());
    status_.set_state(runtime::ComponentState::kRunning);
    if (!frame_writer_.wait_for_readers(
            1, std::chrono::milliseconds(static_cast<int>(options_.wait_subscriber_s * 1e3))) &&
        options_.wait_subscriber_s > 0) {
      log_.info("no subscriber of '", frame_writer_.name(),
                "' yet; publishing anyway (frames before one subscribes are lost)");
    }
    cpu_start_ms_ = process_cpu_ms();
    std::thread capture_thread([this] { capture_loop(); });
    while (!runtime::shutdown_requested()) {
      std::optional<CapturedFrame> frame = slot_.take(kTakePeriod);
      if (frame) {
        publish(*frame);
      } else if (slot_.finished()) {
        break;
      }
    }
    stop_ = true;
    capture_thread.join();
    return finish();
  }

 private:
  static std::string format(double value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%g", value);
    return text;
  }

  void warn(const std::string& kind, const std::string& line) {
    if (kind == "converted") {
      log_.info(line);  // said once by the capture
    } else {
      log_.warn_throttled(kind, line);
    }
  }

  // The capture thread: reads and paces pairs until the source ends, a stop, or bad input. A recording
  // is read (decoded) shortly before its next pair is due, as the replay does, not right after the
  // previous one left: then its decoding does not compete with the consumers' work on that one.
  void capture_loop() {
    StereoCapture& capture = opened_.capture;
    ReplayPacer pacer(options_.rate);
    DecodeLead decode_lead;
    std::optional<std::int64_t> last_time_ns, period_ns;
    try {
      while (!stop_ && !runtime::shutdown_requested()) {
        if (!capture.live() && last_time_ns && period_ns &&
            !wait_until(pacer.due_ns(*last_time_ns + *period_ns) - decode_lead.lead_ns())) {
          break;
        }
        const auto read_start = Clock::now();
        std::optional<CapturedFrame> frame = capture.next();
        if (!frame) break;
        if (!capture.live()) {
          decode_lead.record(std::chrono::duration<double, std::milli>(Clock::now() - read_start).count());
          if (!last_time_ns) pacer.start(frame->source_time_ns, now_ns());
          if (last_time_ns) period_ns = frame->source_time_ns - *last_time_ns;
          last_time_ns = frame->source_time_ns;
          if (!wait_until(pacer.due_ns(frame->source_time_ns))) break;
        }
        if (slot_.put(std::move(*frame))) stats_.count("frames_dropped");
      }
    } catch (const std::exception& error) {
      capture_error_ = error.what();
    }
    source_ended_ = !stop_ && !runtime::shutdown_requested();
    slot_.close();
  }

  bool wait_until(std::int64_t due_ns) {
    for (;;) {
      if (stop_ || runtime::shutdown_requested()) return false;
      const std::int64_t left_ns = due_ns - now_ns();
      if (left_ns <= 0) return true;
      std::this_thread::sleep_for(std::chrono::nanoseconds(std::min(left_ns, kPaceSliceNs)));
    }
  }

  void publish(const CapturedFrame& frame) {
    const msg::StereoFrame message = make_frame_message(frame.images, frame.stamp_ns, frame.right_stamp_ns, seq_);
    {
      auto timer = stats_.time("publish");
      if (frame_writer_.write(message) == runtime::WriteResult::kTimeout) {
        log_.warn_throttled("write_timeouts", "frame ", seq_, ": write timed out (reader too slow)");
      }
    }
    ++seq_;
    stats_.count(runtime::kFramesPublished);
  }

  std::string counts_text() const {
    const CaptureCounts& counts = opened_.capture.counts();
    const double cpu_ms = seq_ > 0 ? (process_cpu_ms() - cpu_start_ms_) / static_cast<double>(seq_) : 0.0;
    char cpu[64];
    std::snprintf(cpu, sizeof(cpu), "; CPU %.2f ms per frame", cpu_ms);
    return std::to_string(seq_) + " frames published, " + std::to_string(slot_.dropped()) + " dropped, " +
           std::to_string(counts.pairing.unpaired_left + counts.pairing.unpaired_right) + " unpaired (" +
           std::to_string(counts.pairing.unpaired_left) + " left, " + std::to_string(counts.pairing.unpaired_right) +
           " right), " + std::to_string(counts.stamps_backwards) + " with stamps going backwards, " +
           std::to_string(counts.unreadable) + " unreadable images" + (seq_ > 0 ? cpu : "");
  }

  int finish() {
    log_.flush_throttled();
    dds_wait_for_acks(frame_writer_.handle(), std::chrono::nanoseconds(kFinalAckTimeout).count());
    const CaptureCounts& counts = opened_.capture.counts();
    stats_.count("frames_unpaired", counts.pairing.unpaired_left + counts.pairing.unpaired_right);
    stats_.count("stamps_backwards", counts.stamps_backwards);
    stats_.count("images_unreadable", counts.unreadable);
    std::string failure;
    if (!capture_error_.empty()) {
      failure = "source failed: " + capture_error_;
    } else if (source_ended_ && (opened_.capture.live() || options_.end_is_failure)) {
      failure = "source ended abnormally: " + opened_.capture.end_reason() +
                (opened_.capture.live() ? "" : " (--end fail: the end of the recording stands for a lost camera)");
    } else if (source_ended_ && seq_ == 0) {
      failure = "published no frame: " + opened_.capture.end_reason();
    }
    const std::string result = counts_text();
    if (!failure.empty()) {
      status_.set_state(runtime::ComponentState::kFailed, failure + "; " + result);
      log_.error(failure, "; ", result);
      return 1;
    }
    const bool stopped = !source_ended_;
    if (stopped && !opened_.capture.live()) {
      // A recording has an end: stopped before it, the run's outputs are a beginning only (its verdict).
      const std::uint64_t used = seq_ + slot_.dropped() + counts.unreadable;
      const std::uint64_t total = opened_.capture.frame_count();
      stats_.count(runtime::kFramesNotPlayed, total > used ? total - used : 1);
    }
    status_.set_state(runtime::ComponentState::kShuttingDown, result + (stopped ? " (stopped)" : ""));
    log_.info(stopped ? "stopped: " : opened_.capture.end_reason() + ": ", result);
    return 0;
  }

  CameraOptions options_;
  runtime::Logger log_;
  Opened opened_;
  CalibrationMessage calibration_message_;
  runtime::Participant participant_;
  runtime::ImageParticipant image_participant_;
  runtime::Topics topics_;
  runtime::Stats stats_;
  // Before the writers, so destroyed after them: its result on the supervisor's pipe (as it goes)
  // comes once their last frames are acknowledged (docs/supervisor.md, Stopping).
  runtime::StatusPublisher status_;
  runtime::Writer<msg::StereoCalibration> calibration_writer_;
  runtime::Writer<msg::StereoFrame> frame_writer_;
  LatestSlot<CapturedFrame> slot_;
  std::atomic<bool> stop_{false};
  std::string capture_error_;  // written by the capture thread before it closes the slot
  std::atomic<bool> source_ended_{false};
  std::uint64_t seq_ = 0;
  double cpu_start_ms_ = 0.0;
};

}  // namespace

int check_camera(const CameraOptions& options) {
  Opened opened(options, [](const std::string&, const std::string&) {});
  if (!opened.capture.live() && !opened.capture.next()) {
    throw std::runtime_error("published no frame: " + opened.capture.end_reason());
  }
  return 0;
}

int run_camera(const runtime::CommonArgs& common, const CameraOptions& options) {
  Camera camera(common, options);
  return camera.run();
}

}  // namespace heslam
