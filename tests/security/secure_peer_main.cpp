// heslam-test-secure-peer: a second DDS participant for the security tests (a process of its own,
// since Cyclone configures a domain once per process). It runs as the identity folder given with
// --identity (plain DDS without it) and either publishes stereo frames whose images are a known byte
// pattern (an honest replay, or an intruder: seq far ahead, like issue 16's stray frame), hostile
// loop corrections, or every hostile sample class of issue 16 section 3 at once (stray frames, a
// different calibration, NaN poses in Odometry, Keyframe and KeyframeState, 100 m corrections), or
// reads stereo frames and counts those carrying the pattern.
//
//   heslam-test-secure-peer --domain N [--namespace NS] [--identity DIR] MODE [--seconds S]
//   MODE: publish-stereo | publish-correction | publish-hostile | read-stereo
//
// Last line: "peer MODE: refused: <reason>" (its writer or reader was not allowed; exit 3), or
// "peer MODE: wrote N" / "peer MODE: received N, M with the pattern" (exit 0). Bad argument: exit 2.
#include <chrono>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "runtime/flags.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "runtime/waitset.hpp"
#include "runtime/writer.hpp"
#include "secure_pattern.hpp"

namespace heslam::test {
namespace {

using namespace std::chrono_literals;

// 20 Hz like a camera.
constexpr auto kPublishPeriod = 50ms;
// An intruder's frames claim to be far ahead of any real replay (issue 16, section 3).
constexpr uint64_t kHostileFirstSeq = 1'000'000;

struct PeerArgs {
  int domain_id = 0;
  std::string ns = "heslam";
  std::string identity;
  std::string mode;
  double seconds = 3.0;
};

PeerArgs parse(int argc, char** argv) {
  PeerArgs args;
  runtime::Flags flags("heslam-test-secure-peer MODE [options]");
  flags.integer("--domain", "N", &args.domain_id, 0, runtime::kMaxDomainId, "DDS domain")
      .text("--namespace", "NAME", &args.ns, "topic namespace")
      .text("--identity", "DIR", &args.identity, "the DDS Security identity")
      .number("--seconds", "S", &args.seconds, 0.0, 86400.0, "how long to run")
      .positional("MODE", "publish-stereo, publish-correction, publish-hostile or read-stereo",
                  [&args](const std::string& arg) {
                    if (!args.mode.empty()) throw std::runtime_error("unexpected argument '" + arg + "'");
                    args.mode = arg;
                  });
  flags.parse(argc, argv);
  if (args.mode != "publish-stereo" && args.mode != "publish-correction" && args.mode != "publish-hostile" &&
      args.mode != "read-stereo") {
    throw std::runtime_error(
        "MODE: expected publish-stereo, publish-correction, publish-hostile or read-stereo, got '" + args.mode + "'");
  }
  return args;
}

template <typename Fn>
bool for_duration(double seconds, Fn fn) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) fn();
  return true;
}

int publish_stereo(runtime::Participant& participant, const runtime::Topics& topics, const PeerArgs& args) {
  runtime::Writer<msg::StereoFrame> writer(participant, topics.stereo());
  std::vector<uint8_t> image = pattern_image(kPatternWidth * kPatternHeight);
  msg::StereoFrame frame{};
  frame.width_px = kPatternWidth;
  frame.height_px = kPatternHeight;
  frame.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(frame.left, image);
  runtime::borrow(frame.right, image);
  uint64_t written = 0;
  for_duration(args.seconds, [&] {
    frame.seq = kHostileFirstSeq + written;
    frame.stamp_ns = static_cast<int64_t>(frame.seq) * 50'000'000;
    frame.stamp_right_ns = frame.stamp_ns;
    writer.write(frame);
    ++written;
    std::this_thread::sleep_for(kPublishPeriod);
  });
  std::cout << "peer " << args.mode << ": wrote " << written << std::endl;
  return 0;
}

msg::LoopCorrection hostile_correction(uint64_t n) {
  msg::LoopCorrection correction{};
  correction.id = (uint64_t{0x7f} << 56) | (n + 1);  // a creator tag no heslam process uses
  correction.map_version = 1;
  correction.loop_keyframe_id = (uint64_t{1} << 56) | 5;
  correction.matched_keyframe_id = (uint64_t{1} << 56) | 1;
  correction.T_matched_loop.position_m[0] = 100.0;  // a 100 m jump: visible in any trajectory
  correction.T_matched_loop.orientation_xyzw[3] = 1.0;
  return correction;
}

int publish_correction(runtime::Participant& participant, const runtime::Topics& topics, const PeerArgs& args) {
  runtime::Writer<msg::LoopCorrection> writer(participant, topics.loop_corrections());
  uint64_t written = 0;
  for_duration(args.seconds, [&] {
    writer.write(hostile_correction(written));
    ++written;
    std::this_thread::sleep_for(kPublishPeriod);
  });
  std::cout << "peer " << args.mode << ": wrote " << written << std::endl;
  return 0;
}

// Issue 16 section 3's hostile classes, each from its own writer, every period.
int publish_hostile(runtime::Participant& participant, const runtime::Topics& topics, const PeerArgs& args) {
  runtime::Writer<msg::StereoFrame> frames(participant, topics.stereo());
  runtime::Writer<msg::StereoCalibration> calibrations(participant, topics.calibration());
  runtime::Writer<msg::Odometry> odometry(participant, topics.odometry());
  runtime::Writer<msg::Keyframe> keyframes(participant, topics.keyframes());
  runtime::Writer<msg::KeyframeState> states(participant, topics.keyframe_states());
  runtime::Writer<msg::LoopCorrection> corrections(participant, topics.loop_corrections());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<uint8_t> image = pattern_image(kPatternWidth * kPatternHeight);
  static char source[] = "intruder";
  uint64_t written = 0;
  for_duration(args.seconds, [&] {
    msg::StereoFrame frame{};
    frame.seq = kHostileFirstSeq + written;
    frame.width_px = kPatternWidth;
    frame.height_px = kPatternHeight;
    frame.encoding = heslam_msg_ENCODING_MONO8;
    runtime::borrow(frame.left, image);
    runtime::borrow(frame.right, image);
    frames.write(frame);
    msg::StereoCalibration calibration{};  // valid shape, another camera: 640x480, f 400 px
    for (msg::CameraModel* camera : {&calibration.left, &calibration.right}) {
      camera->width_px = 640;
      camera->height_px = 480;
      camera->fx_px = camera->fy_px = 400.0;
      camera->cx_px = 320.0;
      camera->cy_px = 240.0;
      for (int i = 0; i < 16; i += 5) camera->T_BS[i] = 1.0;
    }
    calibration.input_rectified = true;
    calibration.source = source;
    calibrations.write(calibration);
    msg::Odometry pose{};
    pose.seq = kHostileFirstSeq + written;
    pose.T_wc.position_m[0] = nan;
    pose.T_wc.orientation_xyzw[3] = 1.0;
    odometry.write(pose);
    msg::Keyframe keyframe{};
    keyframe.id = (uint64_t{0x7f} << 56) | (written + 1);
    keyframe.T_wc.position_m[1] = nan;
    keyframe.T_wc.orientation_xyzw[3] = 1.0;
    keyframes.write(keyframe);
    msg::KeyframeState state{};
    state.id = (uint64_t{1} << 56) | 1;  // the frontend's first keyframe
    state.map_version = 1'000'000 + written;
    state.T_wc.position_m[2] = nan;
    state.T_wc.orientation_xyzw[3] = 1.0;
    states.write(state);
    corrections.write(hostile_correction(written));
    ++written;
    std::this_thread::sleep_for(kPublishPeriod);
  });
  std::cout << "peer " << args.mode << ": wrote " << written << " of each class" << std::endl;
  return 0;
}

int read_stereo(runtime::Participant& participant, const runtime::Topics& topics, const PeerArgs& args) {
  runtime::Reader<msg::StereoFrame> reader(participant, topics.stereo());
  runtime::WaitSet waitset(participant);
  waitset.attach(reader);
  int received = 0, with_pattern = 0;
  for_duration(args.seconds, [&] {
    waitset.wait(100ms);
    for (auto& sample : reader.take()) {
      if (!sample.info.valid_data) continue;
      ++received;
      if (has_pattern(runtime::view(sample.sample->left))) ++with_pattern;
    }
  });
  std::cout << "peer " << args.mode << ": received " << received << ", " << with_pattern << " with the pattern"
            << std::endl;
  return 0;
}

}  // namespace
}  // namespace heslam::test

int main(int argc, char** argv) {
  using namespace heslam;
  test::PeerArgs args;
  try {
    args = test::parse(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "heslam-test-secure-peer: " << error.what() << std::endl;
    return 2;
  }
  try {
    runtime::Participant participant(runtime::ParticipantOptions{args.domain_id, "", args.identity});
    const runtime::Topics topics(args.ns);
    try {
      if (args.mode == "publish-stereo") return test::publish_stereo(participant, topics, args);
      if (args.mode == "publish-correction") return test::publish_correction(participant, topics, args);
      if (args.mode == "publish-hostile") return test::publish_hostile(participant, topics, args);
      return test::read_stereo(participant, topics, args);
    } catch (const std::runtime_error& error) {
      std::cout << "peer " << args.mode << ": refused: " << error.what() << std::endl;
      return 3;
    }
  } catch (const std::exception& error) {
    std::cerr << "heslam-test-secure-peer: " << error.what() << std::endl;
    return 1;
  }
}
