// heslam-test-secure-peer: a second DDS participant for the security tests (a process of its own,
// since Cyclone configures a domain once per process). It runs as the identity folder given with
// --identity (plain DDS without it) and either publishes stereo frames whose images are a known byte
// pattern (an honest replay, or an intruder: seq far ahead, like the hostile tests' stray frame), hostile
// loop corrections, or every hostile sample class at once (stray frames, a
// different calibration, NaN poses in Odometry, Keyframe and KeyframeState, 100 m corrections), or
// reads stereo frames and counts those carrying the pattern.
//
// Or it forges the identity of one of a run's components, with the run id of the
// supervisor --run-of PID copied into its writers' user data (as /proc shows it to anyone):
//   forge-odometry       the frontend's Odometry, a pose 100 m away for each frame it sees (and one
//                        every period while it sees none)
//   forge-status         ComponentStatus named --name (recorder) with --pid (the real one's), RUNNING,
//                        result "tracked 40/40 frames, 0 lost, trajectory /forged/path.txt"
//   forge-frame-done     FrameDone of "frontend" for each frame it sees, at once (and a counting one
//                        every period while it sees none)
//   forge-keyframe-done  KeyframeDone of "local_mapper" with map_version 999999 for each keyframe it
//                        sees (and one for the frontend's next keyframe id every period while none)
//
//   heslam-test-secure-peer --domain N [--namespace NS] [--identity DIR] MODE [--seconds S]
//                           [--run-of PID] [--pid N] [--name NAME]
//   MODE: publish-stereo | publish-correction | publish-hostile | read-stereo | forge-*
//
// Last line: "peer MODE: refused: <reason>" (its writer or reader was not allowed; exit 3), or
// "peer MODE: wrote N" / "peer MODE: received N, M with the pattern" (exit 0). Bad argument: exit 2.
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "runtime/flags.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/run_self.hpp"
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
// An intruder's frames claim to be far ahead of any real replay.
constexpr uint64_t kHostileFirstSeq = 1'000'000;

struct PeerArgs {
  int domain_id = 0;
  std::string ns = "heslam";
  std::string identity;
  std::string mode;
  double seconds = 3.0;
  int run_of = 0;                 // forge-*: copy the run id of this process (a heslam-supervisor)
  int pid = 0;                    // forge-status: the pid claimed
  std::string name = "recorder";  // forge-status: the component claimed
};

// The forged map version.
constexpr uint64_t kForgedMapVersion = 999'999;

PeerArgs parse(int argc, char** argv) {
  PeerArgs args;
  runtime::Flags flags("heslam-test-secure-peer MODE [options]");
  flags.integer("--domain", "N", &args.domain_id, 0, runtime::kMaxDomainId, "DDS domain")
      .text("--namespace", "NAME", &args.ns, "topic namespace")
      .text("--identity", "DIR", &args.identity, "the DDS Security identity")
      .number("--seconds", "S", &args.seconds, 0.0, 86400.0, "how long to run")
      .integer("--run-of", "PID", &args.run_of, 0, std::numeric_limits<int>::max(),
               "forge-*: copy the run id of this process (a heslam-supervisor)")
      .integer("--pid", "PID", &args.pid, 0, std::numeric_limits<int>::max(), "forge-status: the pid claimed")
      .text("--name", "NAME", &args.name, "forge-status: the component claimed")
      .positional("MODE", "publish-stereo, publish-correction, publish-hostile, read-stereo or forge-*",
                  [&args](const std::string& arg) {
                    if (!args.mode.empty()) throw std::runtime_error("unexpected argument '" + arg + "'");
                    args.mode = arg;
                  });
  flags.parse(argc, argv);
  if (args.mode != "publish-stereo" && args.mode != "publish-correction" && args.mode != "publish-hostile" &&
      args.mode != "read-stereo" && args.mode != "forge-odometry" && args.mode != "forge-status" &&
      args.mode != "forge-frame-done" && args.mode != "forge-keyframe-done") {
    throw std::runtime_error(
        "MODE: expected publish-stereo, publish-correction, publish-hostile, read-stereo or forge-*, got '" +
        args.mode + "'");
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

// The hostile sample classes (docs/topics.md, "What subscribers refuse"), each from its own writer, every period.
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

// "<pid>:<start time>" of `pid` (runtime/run_id.hpp): what its children's writers advertise.
std::string run_id_of(int pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  const std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) throw std::runtime_error("--run-of " + std::to_string(pid) + ": no such process");
  std::istringstream fields(text.substr(close + 1));
  std::string field;
  for (int index = 3; index <= 22 && fields >> field; ++index) {
  }  // field 22: start time (proc(5))
  return std::to_string(pid) + ":" + field;
}

// Forges one component's samples (see the file comment) until --seconds pass.
int forge(runtime::Participant& participant, const runtime::Topics& topics, const PeerArgs& args) {
  runtime::Reader<msg::StereoFrame> frames(participant, topics.stereo());
  runtime::Reader<msg::Keyframe> keyframes(participant, topics.keyframes());
  std::optional<runtime::Writer<msg::Odometry>> odometry;
  std::optional<runtime::Writer<msg::ComponentStatus>> status;
  std::optional<runtime::Writer<msg::FrameDone>> frame_done;
  std::optional<runtime::Writer<msg::KeyframeDone>> keyframe_done;
  if (args.mode == "forge-odometry") odometry.emplace(participant, topics.odometry());
  if (args.mode == "forge-status") status.emplace(participant, topics.status());
  if (args.mode == "forge-frame-done") frame_done.emplace(participant, topics.frame_done());
  if (args.mode == "forge-keyframe-done") keyframe_done.emplace(participant, topics.keyframe_done());
  static char frontend[] = "frontend";
  static char mapper[] = "local_mapper";
  static char executable[] = "heslam-recorder";
  static char result[] = "tracked 40/40 frames, 0 lost, trajectory /forged/path.txt";
  std::string name = args.name;
  uint64_t written = 0, blind = 0;
  const auto write_odometry = [&](uint64_t seq, int64_t stamp_ns) {
    msg::Odometry pose{};
    pose.seq = seq;
    pose.stamp_ns = stamp_ns;
    pose.state = heslam_msg_TRACKING_OK;
    pose.T_wc.position_m[0] = 100.0;
    pose.T_wc.orientation_xyzw[3] = 1.0;
    pose.T_ref_c = pose.T_wc;
    odometry->write(pose);
    ++written;
  };
  const auto write_frame_done = [&](uint64_t seq, int64_t stamp_ns) {
    msg::FrameDone done{};
    done.seq = seq;
    done.stamp_ns = stamp_ns;
    done.component = frontend;
    frame_done->write(done);
    ++written;
  };
  const auto write_keyframe_done = [&](uint64_t id) {
    msg::KeyframeDone done{};
    done.keyframe_id = id;
    done.component = mapper;
    done.map_version = kForgedMapVersion;
    keyframe_done->write(done);
    ++written;
  };
  for_duration(args.seconds, [&] {
    bool saw = false;
    for (auto& frame : frames.take()) {
      if (!frame.info.valid_data) continue;
      saw = true;
      if (odometry) write_odometry(frame.sample->seq, frame.sample->stamp_ns);
      if (frame_done) write_frame_done(frame.sample->seq, frame.sample->stamp_ns);
    }
    for (auto& keyframe : keyframes.take()) {
      if (!keyframe.info.valid_data || !keyframe_done) continue;
      saw = true;
      write_keyframe_done(keyframe.sample->id);
    }
    if (status) {
      msg::ComponentStatus sample{};
      sample.name = name.data();
      sample.pid = args.pid;
      sample.executable = executable;
      sample.state = heslam_msg_STATE_RUNNING;
      sample.message = result;
      sample.stamp_ns =
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
              .count();
      status->write(sample);
      ++written;
    }
    if (!saw) {  // blind, as a forger that cannot read (secure mode) would still try
      if (odometry) write_odometry(blind, static_cast<int64_t>(blind) * 50'000'000);
      if (frame_done) write_frame_done(blind, static_cast<int64_t>(blind) * 50'000'000);
      if (keyframe_done) write_keyframe_done((uint64_t{1} << 56) | (blind + 1));
      ++blind;
    }
    std::this_thread::sleep_for(kPublishPeriod);
  });
  std::cout << "peer " << args.mode << ": wrote " << written << std::endl;
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
    // A copied run id: what every Writer of this process then advertises (runtime/run_self.hpp).
    if (args.run_of > 0) setenv(runtime::kJoinRunVariable, test::run_id_of(args.run_of).c_str(), 1);
    runtime::Participant participant(runtime::ParticipantOptions{args.domain_id, "", args.identity});
    const runtime::Topics topics(args.ns);
    try {
      if (args.mode == "publish-stereo") return test::publish_stereo(participant, topics, args);
      if (args.mode == "publish-correction") return test::publish_correction(participant, topics, args);
      if (args.mode == "publish-hostile") return test::publish_hostile(participant, topics, args);
      if (args.mode.rfind("forge-", 0) == 0) return test::forge(participant, topics, args);
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
