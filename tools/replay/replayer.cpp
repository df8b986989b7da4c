// The replay loop: load a pair, wait until it is due (or acknowledged), publish, report progress.
#include "tools/replay/replayer.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <future>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <dds/ddsc/dds_loan_api.h>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/messages/imu.hpp"
#include "runtime/image_transport.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/role_binding.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/sequence.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/status.hpp"
#include "runtime/topics.hpp"
#include "runtime/waitset.hpp"
#include "runtime/writer.hpp"
#include "runtime/writer_identity.hpp"
#include "tools/dataset/imu_reader.hpp"
#include "tools/dataset/stereo_images.hpp"
#include "tools/replay/replay_controls.hpp"
#include "tools/replay/replay_imu.hpp"
#include "tools/replay/replay_messages.hpp"
#include "tools/replay/replay_pacer.hpp"
#include "tools/replay/replay_progress.hpp"

namespace heslam {

namespace {

using Clock = std::chrono::steady_clock;

// Pauses, keys and signals are noticed within this while waiting for a frame to be due.
constexpr std::chrono::milliseconds kControlPollPeriod{20};
// The TTY progress line is redrawn at most this often (a terminal cannot show more anyway).
constexpr std::chrono::milliseconds kProgressPeriod{100};
// At the end, reliable frames still in flight get this long to be acknowledged by readers.
constexpr std::chrono::seconds kFinalAckTimeout{2};
// Lockstep: the role every FrameDone writer claims (one consumer paces the replay), and how many
// acknowledgements of a second writer are kept while the first one is still matched (a restarted
// consumer acknowledges one frame, the one it got again).
constexpr const char* kConsumerRole = "frame consumer";
constexpr std::size_t kMaxHeldAcks = 64;
// Unpaired-row warnings printed one by one before summarising the rest.
constexpr std::size_t kMaxListedWarnings = 5;
// --loop keeps decoded pairs in memory up to this size (the EuRoC clip: 69 MB), so later passes
// cost only the transport; longer recordings are decoded again on every pass.
constexpr std::size_t kMaxLoopCacheBytes = std::size_t{512} << 20;
// --loop with a single-frame recording: gap between passes.
constexpr std::int64_t kSingleFrameLoopGapNs = 100'000'000;

// A pair decoded on the helper thread, or why it could not be.
struct DecodedPair {
  std::optional<StereoImages> images;
  std::string error;
  double decode_ms = 0.0;
};

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

double seconds_between(std::int64_t from_ns, std::int64_t to_ns) { return static_cast<double>(to_ns - from_ns) * 1e-9; }

std::chrono::milliseconds to_ms(double seconds) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000.0));
}

// The TTY progress line: redrawn in place, cleared before any other output.
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)) {}
  ~ProgressLine() { finish(); }

  void update(const ReplayCounts& counts, bool force = false) {
    if (!enabled_) return;
    const auto now = Clock::now();
    if (!force && now - last_draw_ < kProgressPeriod) return;
    last_draw_ = now;
    std::fprintf(stderr, "\r\033[K%s", format_progress_line(counts).c_str());
    std::fflush(stderr);
    drawn_ = true;
  }
  void clear() {
    if (!drawn_) return;
    std::fprintf(stderr, "\r\033[K");
    drawn_ = false;
  }
  void finish() {
    if (!drawn_) return;
    std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  Clock::time_point last_draw_{};
};

// The dataset as the options select it (format, --strict, the time window).
StereoDataset open_replay_dataset(const ReplayOptions& options) {
  DatasetOptions dataset_options;
  dataset_options.format = options.format;
  dataset_options.strict = options.strict;
  dataset_options.calibration_file = options.camera_file;
  StereoDataset dataset = open_dataset(options.dataset, dataset_options);
  select_time_window(dataset, options.start_offset_s, options.duration_s);
  return dataset;
}

// The dataset's imu0/ when it has one and --imu allows it (EuRoC only). A malformed data.csv or
// sensor.yaml throws one line naming the file and the line or field.
std::optional<ImuRecording> open_replay_imu(const ReplayOptions& options, const StereoDataset& dataset) {
  if (!options.imu || dataset.format != DatasetFormat::kEuroc || !has_euroc_imu(dataset.root)) return std::nullopt;
  return read_euroc_imu(dataset.root);
}

ImuCalibration imu_calibration(const ImuRecording& recording) {
  ImuCalibration calibration;
  calibration.noise = recording.noise;
  calibration.rate_hz = recording.rate_hz;
  calibration.T_BS = recording.T_BS;
  calibration.source = (recording.source.parent_path() / "sensor.yaml").string();
  return calibration;
}

class Replay {
 public:
  Replay(const runtime::CommonArgs& common, const ReplayOptions& options)
      : options_(options),
        log_(common.name, common.log_level),
        controls_(options.keyboard),
        dataset_(open(options)),
        rectifier_(dataset_.calibration),
        calibration_message_(dataset_.calibration, rectifier_.camera()),
        participant_({.domain_id = common.domain_id, .dds_config = common.dds_config}),
        image_participant_(participant_, common.image_transport, common.image_domain_id, common.dds_config),
        topics_(common.ns, common.agent_ns),
        status_(participant_, topics_, common.name, stats_),
        calibration_writer_(participant_, topics_.calibration()),
        frame_writer_(image_participant_.get(), topics_.stereo()),
        imu_recording_(open_replay_imu(options, dataset_)),
        progress_(options.progress),
        pacer_(options.rate) {
    if (options_.lockstep) {
      acks_.emplace(participant_, topics_.frame_done());
      ack_waitset_.emplace(participant_);
      ack_waitset_->attach(*acks_);
    }
    if (!options_.turns.empty()) configure_turns(common.agent_ns);
    counts_.total = dataset_.frames.size();
    // Frames per pass, for whoever shows the progress of the whole run (heslam-supervisor).
    stats_.count("frames_total", counts_.total);
    counts_.unpaired_rows = static_cast<std::size_t>(dataset_.skipped_rows);
    if (imu_recording_) {
      imu_.emplace(imu_recording_->samples);
      imu_writer_.emplace(participant_, topics_.imu());
      imu_calibration_writer_.emplace(participant_, topics_.imu_calibration());
    }
  }

  // "" for UDP; for --image-transport shm the images' domain, and whether Cyclone really uses shared
  // memory for the frame writer (it falls back to UDP silently when a QoS or the type does not qualify).
  std::string image_transport_note() {
    if (!image_participant_.separate_domain()) return "";
    const std::string domain = std::to_string(image_participant_.get().domain_id());
    return dds_is_shared_memory_available(frame_writer_.handle())
               ? " (shared memory, domain " + domain + ")"
               : " (domain " + domain + ", shared memory NOT available: Cyclone sends over UDP)";
  }

  int run() {
    announce();
    calibration_writer_.write(calibration_message_.get());
    if (imu_calibration_writer_) {
      imu_calibration_writer_->write(messages::ImuCalibrationMessage(imu_calibration(*imu_recording_)).get());
    }
    status_.set_state(runtime::ComponentState::kRunning);
    preload();
    // Lockstep: the first pair decodes on the helper thread while the consumers start (as each next
    // one does while they work on the previous one), not after they are there.
    if (options_.lockstep && !dataset_.frames.empty()) prefetch(0);
    if (!wait_for_consumer()) return finish();

    const std::int64_t first_stamp_ns = dataset_.frames.front().stamp_ns;
    const std::int64_t pass_offset_step_ns = dataset_.frames.size() > 1
                                                 ? (dataset_.frames.back().stamp_ns - first_stamp_ns) +
                                                       (dataset_.frames.back().stamp_ns - first_stamp_ns) /
                                                           static_cast<std::int64_t>(dataset_.frames.size() - 1)
                                                 : kSingleFrameLoopGapNs;
    start_ns_ = now_ns();
    if (options_.start_paused) set_paused(true);
    std::int64_t pass_offset_ns = 0;
    pacer_.start(first_stamp_ns, now_ns());
    for (;;) {
      counts_.pass_published = 0;
      if (imu_) imu_->start_pass(first_stamp_ns, pass_offset_ns);
      for (std::size_t index = 0; index < dataset_.frames.size(); ++index) {
        const StereoFrameFiles& frame = dataset_.frames[index];
        // Decode shortly before the frame is due (in lockstep: once the previous one is acknowledged),
        // then wait: it leaves at its due time, not due time + PNG decoding, and the decoding does
        // not compete for the cores with the consumers' work on the previous frame.
        if (!options_.lockstep && !is_cached(index) &&
            !wait_until_due(frame.stamp_ns + pass_offset_ns, decode_lead_.lead_ns())) {
          return finish();
        }
        std::optional<StereoImages> images = load(index);
        if (!wait_until_due(frame.stamp_ns + pass_offset_ns)) return finish();
        // Several agents: this frame's turn comes when every other agent's next frame is later.
        if (turn_writer_ && !wait_for_turn(frame.stamp_ns + pass_offset_ns)) return finish();
        // The IMU readings up to this frame leave before it, also for a frame whose images are
        // skipped: the watermark then still advances (docs/topics.md, imu/readings).
        publish_imu(frame.stamp_ns);
        if (!images) continue;
        publish(*images, frame, pass_offset_ns);
        if (acked_at_) record_handshake("lockstep_gap", Clock::now() - *acked_at_, gap_total_);
        // Lockstep: the next pair is decoded on the helper thread while the consumers work on this
        // one (the decoding is then off the handshake's critical path; the bytes are the same).
        if (options_.lockstep && index + 1 < dataset_.frames.size()) prefetch(index + 1);
        if (options_.lockstep) {
          const auto waiting_since = Clock::now();
          if (!wait_for_ack(seq_ - 1, [&] { republish(*images, frame, pass_offset_ns, seq_ - 1); })) return finish();
          acked_at_ = Clock::now();
          record_handshake("ack_wait", *acked_at_ - waiting_since, ack_wait_total_);
        }
        if (quit_) return finish();
      }
      if (!options_.loop) break;
      pass_offset_ns += pass_offset_step_ns;
      ++counts_.pass;
    }
    return finish();
  }

 private:
  static StereoDataset open(const ReplayOptions& options) { return open_replay_dataset(options); }

  // The batch of readings that precede the frame with recording stamp frame_ns (replay_imu.hpp).
  void publish_imu(std::int64_t frame_ns, bool end_of_stream = false) {
    if (!imu_) return;
    const ImuBatchPlan plan = imu_->before_frame(frame_ns);
    const messages::ImuBatchMessage message(plan.samples, imu_seq_, plan.first_index, plan.watermark_ns, end_of_stream);
    if (imu_writer_->write(message.get()) == runtime::WriteResult::kTimeout) {
      log_.warn_throttled("imu_write_timeouts", "IMU batch ", imu_seq_, ": write timed out (reader too slow)");
    }
    ++imu_seq_;
    counts_.imu_readings += plan.samples.size();
    stats_.count("imu_readings_published", plan.samples.size());
  }

  void announce() {
    for (std::size_t i = 0; i < dataset_.warnings.size() && i < kMaxListedWarnings; ++i) {
      log_.warn("skipped row: ", dataset_.warnings[i]);
    }
    if (dataset_.warnings.size() > kMaxListedWarnings) {
      log_.warn("skipped ", dataset_.warnings.size() - kMaxListedWarnings, " more unpaired rows");
    }
    char span[32];
    std::snprintf(span, sizeof(span), "%.2f", dataset_.duration_s());
    char rate[32];
    std::snprintf(rate, sizeof(rate), "rate %g", options_.rate);
    if (imu_recording_) {
      log_.info("IMU: ", imu_recording_->samples.size(), " readings at ", imu_recording_->rate_hz, " Hz from ",
                imu_recording_->source.string(), " on '", imu_writer_->name(), "'");
    } else if (options_.imu && dataset_.format == DatasetFormat::kEuroc) {
      log_.info("IMU: none (no imu0/data.csv in ", dataset_.root.string(), ")");
    }
    log_.info("replaying ", dataset_.root.string(), " (", to_string(dataset_.format), ", ", dataset_.frames.size(),
              " frames, ", span, " s) on domain ", participant_.domain_id(), " as '", frame_writer_.name(), "'",
              image_transport_note(), ", ", options_.lockstep ? "lockstep" : rate);
  }

  // Lockstep: a consumer must read frames and write FrameDone. Rate mode: give readers a moment
  // to match so the first frames are not lost to discovery.
  bool wait_for_consumer() {
    if (!options_.lockstep) {
      if (!frame_writer_.wait_for_readers(1, to_ms(options_.wait_subscriber_s)) && options_.wait_subscriber_s > 0) {
        // Paused from the start nothing is published yet: "publishing anyway" would be wrong.
        if (options_.start_paused) {
          log_.info("no subscriber of '", frame_writer_.name(),
                    "' yet; paused (--start-paused): the first frame goes "
                    "out on resume (space, or kill -USR2 ",
                    getpid(), ") to whoever has subscribed by then");
        } else {
          log_.info("no subscriber of '", frame_writer_.name(),
                    "' yet; publishing anyway (frames before one "
                    "subscribes are lost)");
        }
      }
      return !runtime::shutdown_requested();
    }
    const auto deadline = Clock::now() + to_ms(options_.ack_timeout_s);
    while (frame_writer_.matched_readers() < 1 || acks_->matched_writers() < 1) {
      if (runtime::shutdown_requested()) return false;
      if (Clock::now() >= deadline) {
        throw std::runtime_error("--lockstep: no consumer within " + std::to_string(options_.ack_timeout_s) +
                                 " s (need a reader of '" + frame_writer_.name() + "' and a writer of '" +
                                 acks_->name() + "' on domain " + std::to_string(participant_.domain_id()) +
                                 "; is the frontend running with the same --domain/--namespace?)");
      }
      std::this_thread::sleep_for(kControlPollPeriod);
    }
    return true;
  }

  void set_paused(bool paused) {
    if (paused == pacer_.paused()) return;
    const std::int64_t now = now_ns();
    if (paused) {
      pacer_.pause(now);
      paused_since_ns_ = now;
    } else {
      pacer_.resume(now);
      paused_total_ns_ += now - paused_since_ns_;
    }
    update_counts();
    progress_.update(counts_, true);
    if (!progress_enabled_on_tty()) log_.info(paused ? "paused" : "resumed");
  }

  bool progress_enabled_on_tty() const { return options_.progress && isatty(STDERR_FILENO); }

  void handle_controls() {
    for (const ReplayControl control : controls_.poll()) {
      switch (control) {
        case ReplayControl::kPause: set_paused(true); break;
        case ReplayControl::kResume: set_paused(false); break;
        case ReplayControl::kTogglePause: set_paused(!pacer_.paused()); break;
        case ReplayControl::kQuit: quit_ = true; break;
      }
    }
  }

  // Sleeps until `lead_ns` before the frame is due (rate mode) and while paused; false when asked
  // to stop.
  bool wait_until_due(std::int64_t stamp_ns, std::int64_t lead_ns = 0) {
    for (;;) {
      handle_controls();
      if (quit_ || runtime::shutdown_requested()) return false;
      const std::int64_t due_ns =
          options_.lockstep ? (pacer_.paused() ? INT64_MAX : 0) : pacer_.due_ns(stamp_ns) - lead_ns;
      const std::int64_t now = now_ns();
      if (due_ns <= now) return true;
      update_counts();
      progress_.update(counts_);
      const std::int64_t slice_ns =
          std::min<std::int64_t>(due_ns - now, std::chrono::nanoseconds(kControlPollPeriod).count());
      std::this_thread::sleep_for(std::chrono::nanoseconds(slice_ns));
    }
  }

  bool is_cached(std::size_t index) const { return index < decoded_.size() && decoded_[index].has_value(); }

  // Decodes pair `index` on a helper thread while this one waits. The publishing thread then does
  // no decoding: the scheduler does not charge it that CPU time, so a subscriber's wake-up does not
  // preempt it between the datagrams of a frame (measured: decoding on this thread made each 722 KB
  // write take about 3 ms instead of 0.3-0.5 ms).
  std::future<DecodedPair> decode_on_helper(std::size_t index) const {
    const cv::Size calibrated_size(dataset_.calibration.left.width_px, dataset_.calibration.left.height_px);
    return std::async(std::launch::async, [files = dataset_.frames[index], calibrated_size] {
      DecodedPair pair;
      const auto start = Clock::now();
      try {
        pair.images = load_stereo_images(files, calibrated_size);
      } catch (const std::exception& error) {
        pair.error = error.what();
      }
      pair.decode_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
      return pair;
    });
  }

  // Starts decoding pair `index` on the helper thread; load(index) then takes it from there.
  void prefetch(std::size_t index) {
    if (is_cached(index) || (index < preload_failed_.size() && preload_failed_[index])) return;
    prefetched_.emplace(Prefetched{index, decode_on_helper(index)});
  }

  // --preload: decodes pairs from the first on, before frame 0, while the decoded pairs fit in the
  // budget (the rest are decoded during the run as usual). Pairs that fail are counted and skipped by
  // load() as they would be during the run.
  void preload() {
    if (!(options_.preload_mb > 0.0)) return;
    const auto budget_bytes = static_cast<std::size_t>(options_.preload_mb * 1024.0 * 1024.0);
    const auto start = Clock::now();
    decoded_.resize(dataset_.frames.size());
    std::size_t bytes = 0;
    std::size_t count = 0;
    for (std::size_t index = 0; index < dataset_.frames.size() && !quit_ && !runtime::shutdown_requested(); ++index) {
      const std::optional<StereoImages> images = load(index);
      if (!images) {
        preload_failed_.resize(index + 1);
        preload_failed_[index] = true;  // counted and warned once, here
        continue;
      }
      const std::size_t pair_bytes =
          images->left.total() * images->left.elemSize() + images->right.total() * images->right.elemSize();
      if (bytes + pair_bytes > budget_bytes) {
        decoded_[index].reset();
        break;
      }
      bytes += pair_bytes;
      count = index + 1;
    }
    decoded_.resize(count);  // pairs after the budget are decoded during the run and not kept
    log_.info("preloaded ", count, " of ", dataset_.frames.size(), " pairs (", bytes >> 20, " MiB) in ",
              std::chrono::duration<double>(Clock::now() - start).count(), " s");
  }

  // The pair's images, or nothing when a file is missing or corrupt (counted; fatal with --strict).
  // With --loop, a recording whose decoded pairs fit in kMaxLoopCacheBytes is decoded only once.
  std::optional<StereoImages> load(std::size_t index) {
    if (is_cached(index)) return decoded_[index];
    if (index < preload_failed_.size() && preload_failed_[index]) return std::nullopt;
    DecodedPair pair =
        prefetched_ && prefetched_->index == index ? prefetched_->pair.get() : decode_on_helper(index).get();
    prefetched_.reset();  // a pair prefetched for another index (none today) is dropped
    if (!pair.images) {
      if (options_.strict) throw std::runtime_error(pair.error + " (--strict)");
      ++counts_.skipped_images;
      stats_.count("images_skipped");
      progress_.clear();
      log_.warn_throttled("images_skipped", "skipped frame: ", pair.error);
      return std::nullopt;
    }
    stats_.record_ms("load", pair.decode_ms);
    decode_lead_.record(pair.decode_ms);
    const StereoImages& images = *pair.images;
    if (options_.loop && decoded_.empty()) {
      const std::size_t pair_bytes = images.left.total() * images.left.elemSize() * 2;
      if (pair_bytes * dataset_.frames.size() <= kMaxLoopCacheBytes) decoded_.resize(dataset_.frames.size());
    }
    if (index < decoded_.size()) decoded_[index] = images;  // cv::Mat copies share the pixels
    return pair.images;
  }

  void publish(const StereoImages& images, const StereoFrameFiles& frame, std::int64_t pass_offset_ns) {
    const msg::StereoFrame message =
        make_frame_message(images, frame.stamp_ns + pass_offset_ns, frame.right_stamp_ns + pass_offset_ns, seq_);
    {
      auto timer = stats_.time("publish");
      if (frame_writer_.write(message) == runtime::WriteResult::kTimeout) {
        log_.warn_throttled("write_timeouts", "frame ", seq_, ": write timed out (reader too slow)");
      }
    }
    ++seq_;
    ++counts_.published;
    ++counts_.pass_published;
    stats_.count("frames_published");
    update_counts();
    progress_.update(counts_);
  }

  // The same frame again (same seq), for a consumer that appeared after it was published.
  void republish(const StereoImages& images, const StereoFrameFiles& frame, std::int64_t pass_offset_ns,
                 std::uint64_t seq) {
    const msg::StereoFrame message =
        make_frame_message(images, frame.stamp_ns + pass_offset_ns, frame.right_stamp_ns + pass_offset_ns, seq);
    if (frame_writer_.write(message) == runtime::WriteResult::kTimeout) {
      log_.warn_throttled("write_timeouts", "frame ", seq, ": write timed out (reader too slow)");
    }
    stats_.count("frames_republished");
  }

  // Lockstep: waits for FrameDone(seq); false when asked to stop. Throws when the consumer is silent.
  // A reader of the frames that matches while we wait (a consumer restarted after a crash: the
  // frame was lost with the old process) gets the frame again through `republish`; consumers
  // acknowledge a seq they already processed without processing it again.
  bool wait_for_ack(std::uint64_t seq, const std::function<void()>& republish_frame) {
    const auto deadline = Clock::now() + to_ms(options_.ack_timeout_s);
    std::vector<dds_instance_handle_t> readers = frame_writer_.matched_reader_handles();
    std::sort(readers.begin(), readers.end());
    for (;;) {
      for (auto& received : acks_->take()) {
        // Another run's frontend on the domain acknowledges its own frames, not ours.
        const dds_instance_handle_t writer = received.info.publication_handle;
        if (!received.info.valid_data || !runtime::writer_of_this_run(acks_->handle(), writer)) continue;
        // One consumer paces the replay, whatever name it claims: a second live writer of FrameDone
        // (a forger acknowledging the frames in step) is a conflict (runtime/role_binding.hpp).
        const runtime::RoleBinding::Claim claim =
            consumer_.claim(acks_->handle(), kConsumerRole, writer, received.sample->seq);
        if (claim == runtime::RoleBinding::Claim::kHeld && received.sample->seq >= seq) {
          held_acks_.push_back({writer, received.sample->seq});
          if (held_acks_.size() > kMaxHeldAcks) held_acks_.erase(held_acks_.begin());
        }
        if (claim == runtime::RoleBinding::Claim::kAccepted && received.sample->seq == seq) {
          consumer_.done(seq);
          return true;
        }
      }
      // Acknowledgements of a writer that claimed the consumer's role while the first one was still
      // matched: a restarted consumer's take over once the killed one's lease expired.
      for (auto held = held_acks_.begin(); held != held_acks_.end();) {
        const runtime::RoleBinding::Claim claim =
            held->seq < seq ? runtime::RoleBinding::Claim::kRefused
                            : consumer_.claim(acks_->handle(), kConsumerRole, held->writer, held->seq, /*again=*/true);
        if (claim == runtime::RoleBinding::Claim::kHeld) {
          ++held;
          continue;
        }
        const bool done = claim == runtime::RoleBinding::Claim::kAccepted && held->seq == seq;
        held = held_acks_.erase(held);
        if (done) {
          consumer_.done(seq);
          return true;
        }
      }
      std::vector<dds_instance_handle_t> now_matched = frame_writer_.matched_reader_handles();
      std::sort(now_matched.begin(), now_matched.end());
      if (!std::includes(readers.begin(), readers.end(), now_matched.begin(), now_matched.end())) {
        progress_.clear();
        log_.info("frame seq ", seq, ": a new reader of '", frame_writer_.name(),
                  "' appeared while waiting for its FrameDone (a restarted consumer?); publishing it again");
        republish_frame();
      }
      readers = std::move(now_matched);
      handle_controls();
      if (quit_) return false;
      const auto now = Clock::now();
      if (now >= deadline) {
        throw std::runtime_error("--lockstep: no FrameDone for frame seq " + std::to_string(seq) + " on '" +
                                 acks_->name() + "' within " + std::to_string(options_.ack_timeout_s) +
                                 " s (consumer stopped or too slow; raise --ack-timeout)");
      }
      const auto wait = std::min<Clock::duration>(deadline - now, kControlPollPeriod);
      if (ack_waitset_->wait(wait) == runtime::Wake::kShutdown) return false;
    }
  }

  // Several agents in lockstep (--turns; docs/agents.md): the replays take turns in stamp order through
  // lockstep/turns. Each announces the stamp of the frame it wants to publish next; a replay publishes
  // its frame with stamp t once every other agent has announced a later one (an equal one: the agent
  // listed later goes second). The one with the earliest frame always may go, so no two wait on each
  // other; the frame after an announcement is published only when its own frontend acknowledged the
  // previous one, so all frontends together process one frame at a time, in the same order every run.
  static constexpr std::int64_t kNoMoreFrames = INT64_MAX;

  void configure_turns(const std::string& own) {
    if (!options_.lockstep) throw std::runtime_error("--turns: needs --lockstep (turns pace lockstep replays)");
    const auto self = std::find(options_.turns.begin(), options_.turns.end(), own);
    if (own.empty() || self == options_.turns.end()) {
      throw std::runtime_error("--turns: this replay's agent namespace ('" + own +
                               "', --agent-namespace) is not in the list of turns");
    }
    own_turn_ = own;
    own_turn_index_ = static_cast<std::size_t>(self - options_.turns.begin());
    turn_writer_.emplace(participant_, topics_.turns());
    turn_reader_.emplace(participant_, topics_.turns());
    turn_waitset_.emplace(participant_);
    turn_waitset_->attach(*turn_reader_);
  }

  void announce_turn(std::int64_t next_stamp_ns) {
    msg::FrameDone announcement{};
    announcement.seq = seq_;
    announcement.stamp_ns = next_stamp_ns;
    announcement.component = runtime::borrow(own_turn_);
    turn_writer_->write(announcement);
  }

  // Announces `stamp_ns` and waits for its turn; false when asked to stop. Throws when another agent
  // stays silent for the ack timeout (its replay never started or died).
  bool wait_for_turn(std::int64_t stamp_ns) {
    announce_turn(stamp_ns);
    auto deadline = Clock::now() + to_ms(options_.ack_timeout_s);
    for (;;) {
      for (auto& received : turn_reader_->take()) {
        if (!received.info.valid_data ||
            !runtime::writer_of_this_run(turn_reader_->handle(), received.info.publication_handle)) {
          continue;
        }
        const std::string agent = runtime::to_string(received.sample->component);
        if (agent == own_turn_) continue;
        std::int64_t& next = others_next_[agent];
        if (received.sample->stamp_ns > next) {
          next = received.sample->stamp_ns;
          deadline = Clock::now() + to_ms(options_.ack_timeout_s);  // it is alive and moving
        }
      }
      std::string waiting_for;
      for (std::size_t i = 0; i < options_.turns.size() && waiting_for.empty(); ++i) {
        if (i == own_turn_index_) continue;
        const auto known = others_next_.find(options_.turns[i]);
        const bool later = known != others_next_.end() &&
                           (known->second > stamp_ns || (known->second == stamp_ns && i > own_turn_index_));
        if (!later) waiting_for = options_.turns[i];
      }
      if (waiting_for.empty()) return true;
      handle_controls();
      if (quit_) return false;
      const auto now = Clock::now();
      if (now >= deadline) {
        throw std::runtime_error("--turns: agent '" + waiting_for + "' announced no frame after stamp " +
                                 std::to_string(stamp_ns) + " ns on '" + turn_reader_->name() + "' within " +
                                 std::to_string(options_.ack_timeout_s) +
                                 " s (its replay did not start or stopped; raise --ack-timeout)");
      }
      const auto wait = std::min<Clock::duration>(deadline - now, kControlPollPeriod);
      if (turn_waitset_->wait(wait) == runtime::Wake::kShutdown) return false;
    }
  }

  // Lockstep: a stage time of the handshake, and its sum over the run (the summary line's figures).
  void record_handshake(const char* stage, Clock::duration took, Clock::duration& total) {
    stats_.record_ms(stage, std::chrono::duration<double, std::milli>(took).count());
    total += took;
  }

  // Lockstep: where the wall time went, from the replay's side of the handshake: waiting for the
  // consumer's FrameDone (its work, and the mapper's per keyframe), and from a FrameDone to the next
  // frame written (what the consumers wait for the replay: decoding the pair, unless prefetched, and
  // the write).
  void log_handshake() const {
    if (!options_.lockstep || counts_.published == 0) return;
    const auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
    double ack_median_ms = 0.0;
    double gap_median_ms = 0.0;
    for (const runtime::StageSummary& stage : stats_.stages()) {
      if (stage.name == "ack_wait") ack_median_ms = stage.p50_ms;
      if (stage.name == "lockstep_gap") gap_median_ms = stage.p50_ms;
    }
    char line[200];
    std::snprintf(line, sizeof(line),
                  "lockstep: %.2f s waiting for FrameDone (median %.2f ms), %.2f s from a FrameDone to the "
                  "next frame written (median %.2f ms)",
                  seconds(ack_wait_total_), ack_median_ms, seconds(gap_total_), gap_median_ms);
    log_.info(line);
  }

  void update_counts() {
    const std::int64_t now = now_ns();
    counts_.paused = pacer_.paused();
    counts_.elapsed_s = seconds_between(start_ns_, now);
    counts_.paused_s = seconds_between(0, paused_total_ns_ + (pacer_.paused() ? now - paused_since_ns_ : 0));
  }

  int finish() {
    if (turn_writer_) announce_turn(kNoMoreFrames);  // the other agents go on without this one
    if (imu_ && !runtime::shutdown_requested() && !quit_) {
      // The last batch says no reading follows; its watermark stays where the last frame left it.
      const ImuBatchPlan plan{{}, imu_->published(), imu_->watermark_ns()};
      const messages::ImuBatchMessage message(plan.samples, imu_seq_++, plan.first_index, plan.watermark_ns, true);
      imu_writer_->write(message.get());
      dds_wait_for_acks(imu_writer_->handle(), std::chrono::nanoseconds(kFinalAckTimeout).count());
    }
    update_counts();
    progress_.finish();
    log_.flush_throttled();
    dds_wait_for_acks(frame_writer_.handle(), std::chrono::nanoseconds(kFinalAckTimeout).count());
    const bool stopped_early = runtime::shutdown_requested() || quit_;
    // A recording has an end: stopped before it, the run's outputs are a beginning only (its verdict).
    const std::size_t played = counts_.published + counts_.skipped_images;
    if (stopped_early && !options_.loop && played < counts_.total) {
      stats_.count(runtime::kFramesNotPlayed, counts_.total - played);
    }
    status_.set_state(runtime::ComponentState::kShuttingDown, format_result(counts_, options_.loop, stopped_early));
    log_.info(format_summary(counts_), stopped_early ? " (stopped early)" : "");
    log_handshake();
    // An empty result is never a success: every pair of the sequence was unreadable.
    if (counts_.published == 0 && counts_.skipped_images > 0 && !stopped_early) {
      log_.error("published no frame: all ", counts_.skipped_images,
                 " image pairs were skipped (see the warnings above)");
      return 1;
    }
    return 0;
  }

  ReplayOptions options_;
  runtime::Logger log_;
  ReplayControls controls_;  // first: SIGUSR1/2 must be handled before any reader can see the replay
  StereoDataset dataset_;
  StereoRectifier rectifier_;
  CalibrationMessage calibration_message_;
  runtime::Participant participant_;
  runtime::ImageParticipant image_participant_;  // the frames' (--image-transport shm: a domain of their own)
  runtime::Topics topics_;
  runtime::Stats stats_;
  // Before the writers, so destroyed after them: its result on the supervisor's pipe (as it goes)
  // comes once their last samples are acknowledged (docs/supervisor.md, Stopping).
  runtime::StatusPublisher status_;
  runtime::Writer<msg::StereoCalibration> calibration_writer_;
  runtime::Writer<msg::StereoFrame> frame_writer_;
  std::optional<ImuRecording> imu_recording_;
  std::optional<ReplayImu> imu_;
  std::optional<runtime::Writer<msg::ImuBatch>> imu_writer_;
  std::optional<runtime::Writer<msg::ImuCalibration>> imu_calibration_writer_;
  std::uint64_t imu_seq_ = 0;
  std::optional<runtime::Reader<msg::FrameDone>> acks_;
  std::optional<runtime::WaitSet> ack_waitset_;
  // --turns: this agent's announcements and the others' (their next frame's stamp, by agent namespace)
  std::string own_turn_;
  std::size_t own_turn_index_ = 0;
  std::optional<runtime::Writer<msg::FrameDone>> turn_writer_;
  std::optional<runtime::Reader<msg::FrameDone>> turn_reader_;
  std::optional<runtime::WaitSet> turn_waitset_;
  std::map<std::string, std::int64_t> others_next_;
  runtime::RoleBinding consumer_{log_, stats_, topics_.frame_done().name};
  struct HeldAck {
    dds_instance_handle_t writer;
    std::uint64_t seq;
  };
  std::vector<HeldAck> held_acks_;
  ProgressLine progress_;
  ReplayPacer pacer_;
  ReplayCounts counts_;
  std::vector<std::optional<StereoImages>> decoded_;  // --loop / --preload cache, empty when not caching
  std::vector<bool> preload_failed_;                  // --preload: pairs that could not be decoded
  std::uint64_t seq_ = 0;
  struct Prefetched {
    std::size_t index;
    std::future<DecodedPair> pair;
  };
  std::optional<Clock::time_point> acked_at_;  // lockstep: when the last FrameDone arrived
  Clock::duration ack_wait_total_{};
  Clock::duration gap_total_{};
  std::optional<Prefetched> prefetched_;  // lockstep: the next pair, decoding while the consumers work
  DecodeLead decode_lead_;                // rate mode: how long before its due time a pair is decoded
  std::int64_t start_ns_ = 0;
  std::int64_t paused_since_ns_ = 0;
  std::int64_t paused_total_ns_ = 0;
  bool quit_ = false;
};

}  // namespace

int check_replay(const ReplayOptions& options) {
  const StereoDataset dataset = open_replay_dataset(options);
  const StereoRectifier rectifier(dataset.calibration);
  open_replay_imu(options, dataset);
  return 0;
}

int run_replay(const runtime::CommonArgs& common, const ReplayOptions& options) {
  Replay replay(common, options);
  return replay.run();
}

}  // namespace heslam
