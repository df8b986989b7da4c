// heslam-test-hostile: a mistaken or hostile participant for the hostile-participant tests
// (docs/topics.md, "What subscribers refuse"). On
// --domain N it publishes one sample of each hostile class, each class from its own participant
// (its own GUID prefix, as another process would have), then stays alive --seconds S so its writers
// remain matched (a live second writer, not a dead predecessor) and its reliable samples arrive:
//
//   stray_frame       a valid StereoFrame of the dataset's size with seq 1,000,000
//   malformed_frame   a StereoFrame whose images hold 16 bytes, seq 2,000,000
//   calibration       the dataset's calibration with the left fx 10 % larger (a valid, different one)
//   nan_keyframe      a Keyframe with a NaN pose;  nan_keyframe_state: KeyframeState of fe:999999, NaN pose
//   (wrong_keyframe_state: fe:2) nan_point         MapPointState lm:1 with a NaN position;  nan_odometry: Odometry seq
//   5, NaN pose nan_correction    a LoopCorrection moving fe:1 to a NaN pose wrong_keyframe_state, wrong_odometry:
//   valid samples with a pose 100 m away (only the
//                     single-writer rule keeps these out)
//
//   heslam-test-hostile --domain N --dataset DIR [--seconds S]
// Prints "published N hostile samples" on stdout; exit 1 with one line on error.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "components/core/camera/stereo_rectifier.hpp"
#include "runtime/flags.hpp"
#include "runtime/participant.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/replay/replay_messages.hpp"

namespace {

using namespace heslam;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Discovery of a new participant on loopback takes well under a second; bounded for a run that ended.
constexpr std::chrono::seconds kMatchTimeout{5};
// Ids as heslam allocates them: creator tag in the top byte (components/core/map/ids.hpp).
constexpr std::uint64_t kFrontendTag = std::uint64_t{1} << 56;
constexpr std::uint64_t kMapperTag = std::uint64_t{2} << 56;
constexpr std::uint64_t kForeignTag = std::uint64_t{9} << 56;

msg::Pose pose_at(double x_m, double position_value = 0.0) {
  msg::Pose pose{};
  pose.position_m[0] = x_m;
  pose.position_m[1] = position_value;
  pose.orientation_xyzw[3] = 1.0;
  return pose;
}

msg::Pose nan_pose() {
  msg::Pose pose = pose_at(kNaN, kNaN);
  pose.orientation_xyzw[0] = kNaN;
  return pose;
}

// Each class from its own participant: a separate GUID prefix, like another process.
struct Hostile {
  explicit Hostile(int domain) : participant(runtime::ParticipantOptions{domain, ""}) {}
  runtime::Participant participant;
  std::shared_ptr<void> writer;  // a runtime::Writer<T>; declared last, so deleted before the participant
  std::function<int()> matched_readers;
  std::function<void()> write;  // the sample is copied into the closure (its buffers stay alive in run())
};

template <typename T>
void add(std::vector<std::unique_ptr<Hostile>>& all, int domain, const runtime::TopicSpec<T>& spec, const T& sample) {
  auto hostile = std::make_unique<Hostile>(domain);
  auto writer = std::make_shared<runtime::Writer<T>>(hostile->participant, spec);
  hostile->matched_readers = [writer] { return writer->matched_readers(); };
  hostile->write = [writer, sample] { writer->write(sample); };
  hostile->writer = writer;
  all.push_back(std::move(hostile));
}

int run(int argc, char** argv) {
  int domain = -1;
  std::string dataset_path;
  double seconds = 5.0;
  runtime::Flags flags("heslam-test-hostile --domain N --dataset DIR [--seconds S]");
  flags.integer("--domain", "N", &domain, 0, runtime::kMaxDomainId, "DDS domain")
      .text("--dataset", "DIR", &dataset_path, "the dataset whose calibration sizes the frames")
      .number("--seconds", "S", &seconds, 0.0, 86400.0, "how long to publish");
  flags.parse(argc, argv);
  if (domain < 0 || dataset_path.empty()) throw std::runtime_error("usage: --domain N --dataset DIR [--seconds S]");
  const StereoDataset dataset = open_dataset(dataset_path);
  const runtime::Topics topics;
  std::vector<std::unique_ptr<Hostile>> all;
  int published = 0;

  // A stray frame with a high seq, of the right size (would be tracked and end the run's tracking).
  const int width = dataset.calibration.left.width_px;
  const int height = dataset.calibration.left.height_px;
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(width) * height, 128);
  msg::StereoFrame frame{};
  frame.stamp_ns = frame.stamp_right_ns = 1;
  frame.seq = 1'000'000;
  frame.width_px = static_cast<std::uint32_t>(width);
  frame.height_px = static_cast<std::uint32_t>(height);
  frame.encoding = heslam_msg_ENCODING_MONO8;
  runtime::borrow(frame.left, pixels);
  runtime::borrow(frame.right, pixels);
  add(all, domain, topics.stereo(), frame);
  // A malformed one with an even higher seq.
  std::vector<std::uint8_t> few(16, 0);
  frame.seq = 2'000'000;
  runtime::borrow(frame.left, few);
  runtime::borrow(frame.right, few);
  add(all, domain, topics.stereo(), frame);

  // A valid calibration that differs from the run's.
  StereoCalibration different = dataset.calibration;
  different.left.fx_px *= 1.1;
  different.source = "heslam-test-hostile";
  const CalibrationMessage calibration(different, StereoRectifier(different).camera());
  add(all, domain, topics.calibration(), calibration.get());

  msg::Keyframe keyframe{};
  keyframe.id = kForeignTag | 1;
  keyframe.frame_seq = 3;
  keyframe.T_wc = nan_pose();
  keyframe.camera.fx_px = keyframe.camera.fy_px = 450.0;
  keyframe.camera.baseline_m = 0.11;
  keyframe.camera.width_px = static_cast<std::uint32_t>(width);
  keyframe.camera.height_px = static_cast<std::uint32_t>(height);
  keyframe.pyramid_levels = 8;
  keyframe.scale_factor = 1.2f;
  add(all, domain, topics.keyframes(), keyframe);

  msg::KeyframeState state{};
  // An instance no run writes: readers keep the newest sample per instance (KEEP_LAST(1)), so a NaN state
  // of a real keyframe (fe:1, before) can be replaced by the mapper's next state of it before a reader
  // takes it, which then counts no rejection (the frontend counted none once in a loaded suite).
  state.id = kFrontendTag | 999999;
  state.map_version = 1'000'000;
  state.T_wc = nan_pose();
  add(all, domain, topics.keyframe_states(), state);
  state.id = kFrontendTag | 2;  // another instance: readers keep the newest sample per instance
  state.T_wc = pose_at(100.0);
  add(all, domain, topics.keyframe_states(), state);

  msg::MapPointState point{};
  point.id = kMapperTag | 1;
  point.map_version = 1'000'000;
  point.position_w_m[0] = kNaN;
  add(all, domain, topics.map_points(), point);

  msg::Odometry odometry{};
  odometry.seq = 5;
  odometry.state = heslam_msg_TRACKING_OK;
  odometry.T_wc = nan_pose();
  odometry.T_ref_c = nan_pose();
  add(all, domain, topics.odometry(), odometry);
  odometry.seq = 7;
  odometry.T_wc = pose_at(100.0);
  odometry.T_ref_c = pose_at(100.0);
  add(all, domain, topics.odometry(), odometry);

  std::vector<msg::CorrectedKeyframePose> corrected{{kFrontendTag | 1, nan_pose()}};
  msg::LoopCorrection correction{};
  correction.id = kForeignTag | 7;
  correction.map_version = 1;
  correction.loop_keyframe_id = kFrontendTag | 2;
  correction.matched_keyframe_id = kFrontendTag | 1;
  correction.T_matched_loop = nan_pose();
  correction.kind = heslam_msg_CORRECTION_LOOP;
  runtime::borrow(correction.corrected_poses, corrected);
  add(all, domain, topics.loop_corrections(), correction);

  // All writers first, then one wait for the run's readers (a new participant takes a moment to be
  // discovered), then every sample at once: volatile topics drop what is written before matching.
  const auto deadline = std::chrono::steady_clock::now() + kMatchTimeout;
  for (const auto& hostile : all) {
    while (hostile->matched_readers() < 1 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  for (const auto& hostile : all) {
    hostile->write();
    ++published;
  }
  std::cout << "published " << published << " hostile samples" << std::endl;
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::cerr << "heslam-test-hostile: " << error.what() << "\n";
    return 1;
  }
}
