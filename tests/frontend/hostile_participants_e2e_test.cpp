// Hostile or mistaken participants on the run's domain. A lockstep run of
// config/pipelines/euroc.yaml (loop closer off) on MH01 is run twice: clean, and with
// heslam-test-hostile (each hostile sample class from its own participant: a stray high-seq frame, a
// malformed frame, a different calibration, NaN Keyframe / KeyframeState / MapPointState / Odometry /
// LoopCorrection, and valid but wrong state / odometry) plus a second heslam-replay of the same data
// published mid-run. The trajectory must come out identical (lockstep runs are repeatable) and every
// refusal must be reported and counted. Before the fix, the stray frame alone truncated the run to a
// few poses with exit code 0. The hostile writers are of another run (not started by the run's
// supervisor), so none of them may take a topic over, even when the run's writers exit before the
// recorder while they are still alive (which recorded a hostile pose once in three runs before).
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <signal.h>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/mapping/map_file.hpp"
#include "pipeline_runs.hpp"
#include "runtime/participant.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "test_support.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/replay/replay_messages.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// The hostile participants join once the mapper's map file holds this many keyframes: the run's own
// writers are the first ones then, as they are in any real run (of ~18 keyframes on MH01).
constexpr std::size_t kKeyframesBeforeHostiles = 2;
// How long heslam-test-hostile keeps its writers alive after publishing: second writers must still be
// matched while their samples arrive, and it must not outlive a bounded test by much.
constexpr const char* kHostileSeconds = "6";
// The second replay publishes this many seconds of the recording at the recorded rate (20 Hz). Not
// flat out: the image topic keeps the newest 4 frames of all writers together, so a flood could push
// the run's own frame out of the frontend's reader before it is taken (a denial of service the
// single-writer rule cannot stop; docs/topics.md).
constexpr const char* kSecondReplayDuration_s = "2";

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The trajectory's pose rows (comments dropped).
std::vector<std::string> pose_rows(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> rows;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') rows.push_back(line);
  }
  return rows;
}

std::size_t keyframes_in(const fs::path& map_file) {
  try {
    return load_map_file(map_file).map.keyframes.size();
  } catch (const std::exception&) {
    return 0;  // not written yet
  }
}

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "expected '" << part << "' in the logs";
}

// The value N of "NAME N" in a component's refusal summary at exit; -1 when absent.
long summary_count(const std::string& log, const std::string& name) {
  const std::size_t at = log.rfind(name + " ");
  if (at == std::string::npos) return -1;
  return std::stol(log.substr(at + name.size() + 1));
}

// Every second writer a component met was of another run, and none took a topic over.
void expect_only_other_runs(const std::string& log, const std::string& component) {
  EXPECT_GT(summary_count(log, "second_writers"), 0) << component << ":\n" << log;
  EXPECT_EQ(summary_count(log, "other_run_writers"), summary_count(log, "second_writers")) << component << ":\n" << log;
  EXPECT_EQ(log.find("takes over"), std::string::npos) << component << ":\n" << log;
}

TEST(HostileParticipants, LockstepRunIsUnchangedAndEveryRefusalIsCounted) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("hostile");
  const int domain = test::exclusive_domain_id();

  auto clean = test::start_pipeline("euroc", dataset, dir.path(), "clean", domain, {"loop_closer=none"});
  ASSERT_EQ(test::finish(*clean), 0) << clean->out() << clean->err();
  const std::vector<std::string> clean_rows = pose_rows(dir.path() / "clean.txt");
  ASSERT_EQ(clean_rows.size(), 160u);

  auto run = test::start_pipeline("euroc", dataset, dir.path(), "hostile", domain, {"loop_closer=none"});
  const fs::path map_file = dir.path() / "hostile.map";  // STEM.map beside hostile.txt
  const auto deadline = std::chrono::steady_clock::now() + test::kPipelineTimeout;
  while (keyframes_in(map_file) < kKeyframesBeforeHostiles && std::chrono::steady_clock::now() < deadline &&
         !run->wait(std::chrono::milliseconds(0))) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GE(keyframes_in(map_file), kKeyframesBeforeHostiles) << run->out() << run->err();
  const std::string domain_arg = std::to_string(domain);
  test::ChildProcess hostile(test::bin_dir() / "heslam-test-hostile",
                             {"--domain", domain_arg, "--dataset", dataset.string(), "--seconds", kHostileSeconds},
                             dir.path(), "hostile_publisher");
  test::ChildProcess second_replay(test::bin_dir() / "heslam-replay",
                                   {dataset.string(), "--rate", "1", "--duration", kSecondReplayDuration_s, "--wait",
                                    "1", "--no-progress", "--no-keyboard", "--domain", domain_arg},
                                   dir.path(), "second_replay");

  ASSERT_EQ(test::finish(*run), 0) << run->out() << run->err();
  EXPECT_EQ(hostile.wait(test::kStopTimeout).value_or(-1), 0) << hostile.err();
  EXPECT_NE(hostile.out().find("published 10 hostile samples"), std::string::npos) << hostile.out() << hostile.err();
  second_replay.wait(test::kStopTimeout);
  const std::string output = run->out() + run->err();
  const std::string frontend_log = read_file(dir.path() / "logs_hostile/frontend.log");
  const std::string recorder_log = read_file(dir.path() / "logs_hostile/recorder.log");
  const std::string mapper_log = read_file(dir.path() / "logs_hostile/local_mapper.log");

  // The same trajectory, pose for pose (lockstep runs are repeatable to the last digit).
  const std::vector<std::string> rows = pose_rows(dir.path() / "hostile.txt");
  ASSERT_EQ(rows.size(), clean_rows.size()) << output;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i], clean_rows[i]) << "pose " << i << " differs from the clean run's";
  }

  // One clear line per second writer, naming the topic; and the counts at exit.
  expect_contains(frontend_log, "topic 'heslam/camera/stereo': a second writer");
  expect_contains(frontend_log, "topic 'heslam/camera/calibration': a second writer");
  expect_contains(frontend_log, "topic 'heslam/map/keyframe_states': a second writer");
  expect_contains(frontend_log, "rejected_keyframe_states 1");
  expect_contains(frontend_log, "rejected_points 1");
  expect_contains(frontend_log, "second_writer_samples");
  EXPECT_EQ(frontend_log.find("calibration changed"), std::string::npos) << frontend_log;
  expect_contains(recorder_log, "topic 'heslam/odometry': rejected a sample");
  expect_contains(recorder_log, "rejected_odometry 1");
  expect_contains(recorder_log, "rejected_keyframes 1");
  expect_contains(recorder_log, "rejected_keyframe_states 1");
  expect_contains(recorder_log, "topic 'heslam/odometry': a second writer");
  expect_contains(mapper_log, "topic 'heslam/map/keyframes': a second writer");
  // loop/corrections has no writer in this run (loop_closer=none): its NaN correction, of another
  // run, is refused before it is read, where it used to own the topic and be counted as bad.
  expect_contains(mapper_log, "topic 'heslam/loop/corrections': a writer of another run");
  expect_contains(mapper_log, "0 bad corrections");
  expect_only_other_runs(frontend_log, "frontend");
  expect_only_other_runs(recorder_log, "recorder");
  EXPECT_EQ(mapper_log.find("takes over"), std::string::npos) << mapper_log;
}

// Polls a child's stderr for `part` (bounded: discovery and start-up take a moment).
bool err_contains_within(const test::ChildProcess& child, const std::string& part, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (child.err().find(part) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// The calibration's writer went away and another writer took the topic over (as a restarted replay
// would): the same calibration from it is fine, a different one is refused with an error line.
TEST(HostileParticipants, ADifferentCalibrationFromAnotherWriterIsRefusedEvenAfterATakeOver) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset_path = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("calibration_writer");
  const int domain = test::exclusive_domain_id();
  const StereoDataset dataset = open_dataset(dataset_path);
  StereoCalibration different = dataset.calibration;
  different.left.fx_px *= 1.1;
  different.source = "another writer";
  const CalibrationMessage first_message(dataset.calibration, StereoRectifier(dataset.calibration).camera());
  const CalibrationMessage different_message(different, StereoRectifier(different).camera());
  const runtime::Topics topics;

  test::ChildProcess frontend(
      test::bin_dir() / "heslam-frontend",
      {"--domain", std::to_string(domain), "--config", (test::source_dir() / "config/frontend/euroc.yaml").string()},
      dir.path(), "frontend");
  runtime::Participant second(runtime::ParticipantOptions{domain, ""});
  runtime::Writer<msg::StereoCalibration> second_writer(second, topics.calibration());
  {
    runtime::Participant first(runtime::ParticipantOptions{domain, ""});
    runtime::Writer<msg::StereoCalibration> first_writer(first, topics.calibration());
    ASSERT_TRUE(first_writer.wait_for_readers(1, std::chrono::seconds(30))) << frontend.err();
    first_writer.write(first_message.get());
    ASSERT_TRUE(err_contains_within(frontend, "': rectified ", std::chrono::seconds(30))) << frontend.err();
  }  // the run's calibration writer leaves
  ASSERT_TRUE(second_writer.wait_for_readers(1, std::chrono::seconds(10)));
  second_writer.write(different_message.get());
  EXPECT_TRUE(
      err_contains_within(frontend, "refused a different calibration ('another writer'", std::chrono::seconds(10)))
      << frontend.err();
  frontend.signal(SIGTERM);
  EXPECT_EQ(frontend.wait(test::kStopTimeout).value_or(-1), 0) << frontend.err();
  const std::string err = frontend.err();
  EXPECT_NE(err.find("refused_calibrations 1"), std::string::npos) << err;
  EXPECT_EQ(err.find("calibration changed"), std::string::npos) << err;
}

}  // namespace
}  // namespace heslam
