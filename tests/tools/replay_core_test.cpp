// heslam-replay's DDS-free parts: pacing with rate and pauses, progress text, option parsing.
#include <stdexcept>

#include <gtest/gtest.h>

#include "tools/replay/replay_imu.hpp"
#include "tools/replay/replay_options.hpp"
#include "tools/replay/replay_pacer.hpp"
#include "tools/replay/replay_progress.hpp"

namespace heslam {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(DecodeLead, TwiceTheRunningEstimatePlusAMargin) {
  DecodeLead lead;
  EXPECT_EQ(lead.lead_ns(), 22 * kMs);  // 2 x 10 ms (the initial estimate) + 2 ms
  lead.record(5.0);                     // 10 + 0.2 x (5 - 10) = 9 ms
  EXPECT_EQ(lead.lead_ns(), 20 * kMs);
}

TEST(ReplayPacer, RealTimeDoubleSpeedAndFlatOut) {
  ReplayPacer real_time(1.0);
  real_time.start(5000 * kMs, 100 * kMs);
  EXPECT_EQ(real_time.due_ns(5000 * kMs), 100 * kMs);
  EXPECT_EQ(real_time.due_ns(5050 * kMs), 150 * kMs);
  ReplayPacer twice(2.0);
  twice.start(5000 * kMs, 100 * kMs);
  EXPECT_EQ(twice.due_ns(5100 * kMs), 150 * kMs);
  ReplayPacer flat_out(0.0);
  flat_out.start(5000 * kMs, 100 * kMs);
  EXPECT_EQ(flat_out.due_ns(9000 * kMs), 100 * kMs);
}

TEST(ReplayPacer, PauseShiftsEverythingAfterIt) {
  ReplayPacer pacer(1.0);
  pacer.start(0, 1000 * kMs);
  pacer.pause(1020 * kMs);
  EXPECT_TRUE(pacer.paused());
  EXPECT_EQ(pacer.due_ns(50 * kMs), INT64_MAX);
  pacer.pause(1030 * kMs);  // idempotent: the first pause time counts
  pacer.resume(1520 * kMs);
  EXPECT_FALSE(pacer.paused());
  EXPECT_EQ(pacer.due_ns(50 * kMs), 1550 * kMs);  // 500 ms paused
  pacer.resume(2000 * kMs);                       // idempotent
  EXPECT_EQ(pacer.due_ns(50 * kMs), 1550 * kMs);
}

TEST(ReplayPacer, StartPausedWaitsForResume) {
  ReplayPacer pacer(1.0);
  pacer.pause(0);
  pacer.start(0, 100 * kMs);
  pacer.resume(400 * kMs);
  EXPECT_EQ(pacer.due_ns(0), 400 * kMs);
}

TEST(ReplayProgress, LineAndSummary) {
  ReplayCounts counts;
  counts.published = 40;
  counts.pass_published = 40;
  counts.total = 95;
  counts.elapsed_s = 2.5;
  counts.paused_s = 0.5;
  EXPECT_EQ(format_progress_line(counts), "frame 40/95   42%  20.0 fps  ETA 2.8 s");
  counts.paused = true;
  counts.pass = 2;
  counts.skipped_images = 1;
  EXPECT_EQ(format_progress_line(counts), "frame 40/95   42%  20.0 fps  ETA 2.8 s  pass 2  skipped 1  [paused]");
  counts.unpaired_rows = 4;
  EXPECT_EQ(format_summary(counts),
            "published 40 frames in 2.00 s (20.0 fps) over 2 passes; skipped 1 images; 4 unpaired rows");
  counts.imu_readings = 401;
  EXPECT_EQ(format_summary(counts),
            "published 40 frames in 2.00 s (20.0 fps) over 2 passes; skipped 1 images; 4 "
            "unpaired rows; 401 IMU readings");
}

std::string option_error(const std::vector<std::string>& args) {
  try {
    parse_replay_options(args);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(ReplayOptions, ParsesEveryOption) {
  const ReplayOptions options = parse_replay_options({"/data/V101", "--format", "euroc", "--rate", "0.5", "--loop",
                                                      "--start-offset", "1.5", "--duration", "2", "--start-paused",
                                                      "--strict", "--wait", "0", "--no-progress", "--preload", "200"});
  EXPECT_EQ(options.dataset, "/data/V101");
  EXPECT_EQ(options.format, DatasetFormat::kEuroc);
  EXPECT_DOUBLE_EQ(options.rate, 0.5);
  EXPECT_TRUE(options.loop);
  EXPECT_DOUBLE_EQ(options.start_offset_s, 1.5);
  EXPECT_DOUBLE_EQ(options.duration_s, 2.0);
  EXPECT_TRUE(options.start_paused);
  EXPECT_TRUE(options.strict);
  EXPECT_DOUBLE_EQ(options.wait_subscriber_s, 0.0);
  EXPECT_FALSE(options.progress);
  EXPECT_FALSE(options.lockstep);
  EXPECT_DOUBLE_EQ(options.preload_mb, 200.0);
  EXPECT_DOUBLE_EQ(parse_replay_options({"d"}).preload_mb, 0.0);  // off unless asked
  const ReplayOptions lockstep = parse_replay_options({"d", "--lockstep", "--ack-timeout", "3"});
  EXPECT_TRUE(lockstep.lockstep);
  EXPECT_DOUBLE_EQ(lockstep.ack_timeout_s, 3.0);
  EXPECT_TRUE(parse_replay_options({"d"}).imu);  // imu0/ published when present
  EXPECT_TRUE(parse_replay_options({"d", "--imu", "auto"}).imu);
  EXPECT_FALSE(parse_replay_options({"d", "--imu", "none"}).imu);
  EXPECT_FALSE(parse_replay_options({"d", "--no-imu"}).imu);
}

// Pipeline files give the toggles as values ($(arg loop), $(arg start_paused): on or off).
TEST(ReplayOptions, TheTogglesAlsoTakeOnOrOff) {
  const ReplayOptions on = parse_replay_options({"d", "--loop-mode", "on", "--start-paused-mode", "on"});
  EXPECT_TRUE(on.loop);
  EXPECT_TRUE(on.start_paused);
  const ReplayOptions off = parse_replay_options({"d", "--loop-mode", "off", "--start-paused-mode", "off"});
  EXPECT_FALSE(off.loop);
  EXPECT_FALSE(off.start_paused);
  EXPECT_EQ(option_error({"d", "--loop-mode", "yes"}), "--loop-mode: expected on or off, got 'yes'");
}

TEST(ReplayOptions, EachBadOptionHasItsMessage) {
  EXPECT_EQ(option_error({}), "missing DATASET argument (see --help)");
  EXPECT_EQ(option_error({"d", "--rate", "fast"}), "--rate: expected a number in [0, 100], got 'fast'");
  EXPECT_EQ(option_error({"d", "--rate"}), "--rate: missing value");
  EXPECT_EQ(option_error({"d", "--preload", "-1"}), "--preload: expected a number in [0, 1e+06], got '-1'");
  EXPECT_EQ(option_error({"d", "--format", "bag"}), "--format: unknown format 'bag' (expected euroc, kitti or auto)");
  EXPECT_EQ(option_error({"d", "--lockstep", "--rate", "1"}),
            "--rate and --lockstep exclude each other (lockstep is paced by the consumer)");
  EXPECT_EQ(option_error({"d", "--imu", "yes"}), "--imu: expected auto or none, got 'yes'");
  EXPECT_EQ(option_error({"d", "--bogus"}), "--bogus: unknown option (see --help)");
  EXPECT_EQ(option_error({"d", "e"}), "'e': unexpected second dataset argument (the first is 'd'; see --help)");
}

// Every number has a range: a huge value is refused, not turned into an overflowing duration.
// Before: --ack-timeout 1e308 timed out at once (printed with 309 digits) and --rate 1e308 ran.
TEST(ReplayOptions, EveryNumberHasARangeAndABadValueIsQuotedShort) {
  EXPECT_EQ(option_error({"d", "--ack-timeout", "1e308", "--lockstep"}),
            "--ack-timeout: expected a number in [0.001, 86400], got '1e308'");
  EXPECT_EQ(option_error({"d", "--rate", "1e308"}), "--rate: expected a number in [0, 100], got '1e308'");
  EXPECT_EQ(option_error({"d", "--wait", "1e9"}), "--wait: expected a number in [0, 86400], got '1e9'");
  EXPECT_EQ(option_error({"d", "--duration", "inf"}), "--duration: expected a number in [0, 1e+06], got 'inf'");
  const std::string huge(100000, '9');
  const std::string error = option_error({"d", "--start-offset", huge.c_str()});
  EXPECT_EQ(error,
            "--start-offset: expected a number in [0, 1e+06], got '" + std::string(80, '9') + "... (100000 bytes)'");
}

// The replay's result on the run's last line: what it published of the recording, and what it skipped.
TEST(ReplayProgress, ResultSaysWhatWasPublishedAndSkipped) {
  ReplayCounts counts;
  counts.total = 160;
  counts.published = 160;
  EXPECT_EQ(format_result(counts, false, false), "160 of 160 frames published");
  counts.published = 159;
  counts.skipped_images = 1;
  EXPECT_EQ(format_result(counts, false, false), "159 of 160 frames published, 1 skipped (a missing or corrupt image)");
  counts.published = 40;
  counts.skipped_images = 0;
  EXPECT_EQ(format_result(counts, false, true), "40 of 160 frames published (stopped early)");
  counts.published = 480;
  counts.pass = 3;
  EXPECT_EQ(format_result(counts, true, false), "published 480 frames over 3 passes");
}

}  // namespace
}  // namespace heslam

namespace heslam {
namespace {

// IMU readings every 5 ms from 0 to 100 ms; frames at 12.5, 37.5, 50 ms.
std::vector<ImuSample> imu_recording() {
  std::vector<ImuSample> samples;
  for (std::int64_t stamp = 0; stamp <= 100'000'000; stamp += 5'000'000) {
    ImuSample sample;
    sample.stamp_ns = stamp;
    samples.push_back(sample);
  }
  return samples;
}

TEST(ReplayImu, EachFrameGetsTheReadingsUpToTheFirstAtOrAfterIt) {
  const std::vector<ImuSample> recording = imu_recording();
  ReplayImu imu(recording);
  imu.start_pass(12'500'000, 0);
  const ImuBatchPlan first = imu.before_frame(12'500'000);
  ASSERT_EQ(first.samples.size(), 2u);  // 10 ms (at or before the first frame), 15 ms (after it)
  EXPECT_EQ(first.samples.front().stamp_ns, 10'000'000);
  EXPECT_EQ(first.first_index, 0u);
  EXPECT_EQ(first.watermark_ns, 15'000'000);
  const ImuBatchPlan second = imu.before_frame(37'500'000);
  ASSERT_EQ(second.samples.size(), 5u);  // 20 .. 40 ms
  EXPECT_EQ(second.first_index, 2u);
  EXPECT_EQ(second.watermark_ns, 40'000'000);
  const ImuBatchPlan third = imu.before_frame(50'000'000);  // a frame on an IMU stamp
  ASSERT_EQ(third.samples.size(), 2u);                      // 45, 50 ms
  EXPECT_EQ(third.watermark_ns, 50'000'000);
  // A frame after the recording ended (an IMU that stopped): no readings, the watermark still moves.
  ReplayImu short_imu(std::span<const ImuSample>(recording).first(3));  // 0, 5, 10 ms
  short_imu.start_pass(0, 0);
  EXPECT_EQ(short_imu.before_frame(7'000'000).samples.size(), 3u);
  const ImuBatchPlan after_end = short_imu.before_frame(30'000'000);
  EXPECT_EQ(after_end.samples.size(), 0u);
  EXPECT_EQ(after_end.watermark_ns, 30'000'000);
  EXPECT_TRUE(short_imu.before_frame(60'000'000).samples.empty());
  EXPECT_EQ(short_imu.watermark_ns(), 60'000'000);
}

TEST(ReplayImu, LoopPassesKeepStampsIncreasing) {
  const std::vector<ImuSample> recording = imu_recording();
  ReplayImu imu(recording);
  imu.start_pass(0, 0);
  imu.before_frame(0);
  const ImuBatchPlan end = imu.before_frame(97'000'000);
  EXPECT_EQ(end.samples.back().stamp_ns, 100'000'000);
  imu.start_pass(0, 100'000'000);  // pass 2 starts at 100 ms: the 100 ms reading is not repeated
  const ImuBatchPlan again = imu.before_frame(0);
  ASSERT_EQ(again.samples.size(), 0u);
  EXPECT_EQ(again.watermark_ns, 100'000'000);
  const ImuBatchPlan next = imu.before_frame(10'000'000);
  ASSERT_EQ(next.samples.size(), 2u);
  EXPECT_EQ(next.samples.front().stamp_ns, 105'000'000);
  EXPECT_EQ(next.first_index, end.first_index + end.samples.size());
}

}  // namespace
}  // namespace heslam
