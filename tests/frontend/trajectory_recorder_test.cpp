// The recorder's trajectory rebuilding: frames follow their reference keyframe's final pose (as
// ORB-SLAM2 saves it), culled keyframes follow their parent, untracked frames are listed, not invented.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/run_journal.hpp"
#include "tools/eval/trajectory_io.hpp"
#include "tools/recorder/frame_journal.hpp"
#include "tools/recorder/recorder.hpp"
#include "tools/recorder/trajectory_recorder.hpp"

namespace heslam::recorder {
namespace {

Pose3 translation(double x, double y, double z) {
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

RecordedFrame tracked(std::uint64_t seq, KeyframeId reference, const Pose3& T_ref_c, const Pose3& T_wc) {
  RecordedFrame frame;
  frame.seq = seq;
  frame.stamp_ns = 1'000'000'000 + static_cast<std::int64_t>(seq) * 50'000'000;
  frame.tracked = true;
  frame.state = "OK";
  frame.reference = reference;
  frame.T_ref_c = T_ref_c;
  frame.T_wc = T_wc;
  return frame;
}

TEST(TrajectoryRecorder, UnmovedReferenceKeepsTheOdometryPoseBitForBit) {
  TrajectoryRecorder recorder;
  Pose3 T_wc = translation(0.1, 0.2, 0.3);
  T_wc.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Pose3 T_wk = translation(1, 0, 0);
  recorder.add_keyframe(1, 0, 0, T_wk);
  recorder.add_frame(tracked(0, 1, T_wk.inverse() * T_wc, T_wc));
  const RecordedTrajectories out = recorder.build();
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_EQ(out.frames.poses_wc[0].matrix(), T_wc.matrix());
  EXPECT_DOUBLE_EQ(out.frames.stamps_s[0], 1.0);
}

TEST(TrajectoryRecorder, RefinedReferenceMovesItsFrames) {
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 0, 0, translation(1, 0, 0));
  recorder.add_frame(tracked(3, 1, translation(0, 0.5, 0), translation(1, 0.5, 0)));
  recorder.update_keyframe(1, translation(1.5, 0, 0), kNoId, false);  // the mapper refined it
  const RecordedTrajectories out = recorder.build();
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_TRUE(out.frames.poses_wc[0].translation().isApprox(Eigen::Vector3d(1.5, 0.5, 0)));
  EXPECT_EQ(out.frames.frame_ids[0], 3);
  ASSERT_EQ(out.keyframes.size(), 1u);
  EXPECT_TRUE(out.keyframes.poses_wc[0].translation().isApprox(Eigen::Vector3d(1.5, 0, 0)));
}

TEST(TrajectoryRecorder, CulledKeyframeFollowsItsParent) {
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 0, 0, translation(0, 0, 0));
  recorder.add_keyframe(2, 10, 5, translation(1, 0, 0));
  recorder.add_frame(tracked(6, 2, translation(0, 0, 1), translation(1, 0, 1)));
  recorder.update_keyframe(2, translation(1, 0, 0), 1, true);       // culled, parent 1
  recorder.update_keyframe(1, translation(0, 2, 0), kNoId, false);  // parent moved afterwards
  const RecordedTrajectories out = recorder.build();
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_TRUE(out.frames.poses_wc[0].translation().isApprox(Eigen::Vector3d(1, 2, 1)));
  EXPECT_EQ(out.keyframes.size(), 1u);  // culled keyframes are not in the keyframe trajectory
}

// Recorder and frontend killed together: the Keyframe samples died with the frontend, the mapper's
// states carry no stamp; the odometry of the frame that created the keyframe (republished from the
// frontend's journal) gives its stamp and frame. A Keyframe sample wins over it.
TEST(TrajectoryRecorder, KeyframeWithoutItsSampleTakesItsStampFromTheCreatingFrame) {
  TrajectoryRecorder recorder;
  recorder.update_keyframe(1, translation(1.5, 0, 0), kNoId, false);  // only the mapper's state
  recorder.add_keyframe_frame(1, 2'000'000'000, 20, translation(1, 0, 0));
  recorder.add_keyframe(2, 3'000'000'000, 30, translation(2, 0, 0));
  recorder.add_keyframe_frame(2, 9'000'000'000, 90, translation(9, 0, 0));  // the sample wins
  const RecordedTrajectories out = recorder.build();
  ASSERT_EQ(out.keyframes.size(), 2u);
  EXPECT_DOUBLE_EQ(out.keyframes.stamps_s[0], 2.0);
  EXPECT_EQ(out.keyframes.frame_ids[0], 20);
  EXPECT_TRUE(out.keyframes.poses_wc[0].translation().isApprox(Eigen::Vector3d(1.5, 0, 0)));  // the state's pose
  EXPECT_DOUBLE_EQ(out.keyframes.stamps_s[1], 3.0);
  EXPECT_EQ(out.keyframes.frame_ids[1], 30);
  EXPECT_TRUE(out.keyframes.poses_wc[1].translation().isApprox(Eigen::Vector3d(2, 0, 0)));
}

TEST(TrajectoryRecorder, UntrackedFramesAreListedNotInvented) {
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 0, 0, Pose3::Identity());
  recorder.add_frame(tracked(0, 1, Pose3::Identity(), Pose3::Identity()));
  RecordedFrame lost;
  lost.seq = 1;
  lost.stamp_ns = 5;
  lost.state = "LOST";
  recorder.add_frame(lost);
  recorder.add_frame(tracked(2, 7, Pose3::Identity(), translation(0, 0, 2)));  // keyframe 7 never arrived
  const RecordedTrajectories out = recorder.build();
  EXPECT_EQ(out.frames.size(), 2u);
  ASSERT_EQ(out.lost.size(), 1u);
  EXPECT_EQ(out.lost[0].seq, 1u);
  EXPECT_EQ(out.lost[0].state, "LOST");
  EXPECT_EQ(out.frames_without_reference, 1);
  EXPECT_EQ(out.frames.poses_wc[1].translation().z(), 2.0);
}

TEST(RecorderFiles, WritesTrajectoryKeyframesAndLostListInTheChosenFormat) {
  const auto dir = std::filesystem::temp_directory_path() / ("heslam_recorder_test_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 1'000'000'000, 0, translation(0, 0, 0));
  recorder.add_frame(tracked(0, 1, translation(0, 0, 0), translation(0, 0, 0)));
  recorder.add_frame(tracked(1, 1, translation(0.1, 0, 0), translation(0.1, 0, 0)));
  const RecorderOptions options = RecorderOptions::from(
      runtime::Config::empty(), {"--output", (dir / "sub/run.csv").string(), "--format", "euroc"});
  EXPECT_EQ(options.keyframe_output, dir / "sub/run.keyframes.csv");
  EXPECT_EQ(options.lost_output, dir / "sub/run.lost.txt");
  write_recording(recorder.build(), options);
  const eval::Trajectory back = eval::read_trajectory(options.output);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_NEAR(back.poses_wc[1].translation().x(), 0.1, 1e-12);
  EXPECT_TRUE(std::filesystem::exists(options.lost_output));
  std::filesystem::remove_all(dir);

  EXPECT_THROW(RecorderOptions::from(runtime::Config::empty(), {"--format", "ply"}), std::runtime_error);
  EXPECT_THROW(RecorderOptions::from(runtime::Config::empty(), {"--output"}), std::runtime_error);
}

// The atlas: a frame's map is its reference keyframe's latest (a merge renumbers it), else the
// odometry's; STEM.maps.txt is written only when the run had several maps, one line per pose.
TEST(RecorderFiles, MapsFileSaysWhichMapEachPoseIsIn) {
  const auto dir = std::filesystem::temp_directory_path() / ("heslam_recorder_maps_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  const RecorderOptions options =
      RecorderOptions::from(runtime::Config::empty(), {"--output", (dir / "run.txt").string()});
  EXPECT_EQ(options.maps_output, dir / "run.maps.txt");
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 1'000'000'000, 0, translation(0, 0, 0));
  recorder.add_frame(tracked(0, 1, translation(0, 0, 0), translation(0, 0, 0)));
  write_recording(recorder.build(), options);
  EXPECT_FALSE(std::filesystem::exists(options.maps_output)) << "one map: no maps file";

  recorder.add_keyframe(2, 1'100'000'000, 2, translation(0.2, 0, 0));
  recorder.set_keyframe_map(2, 1);
  RecordedFrame second_map = tracked(2, 2, translation(0, 0, 0), translation(0.2, 0, 0));
  second_map.map_id = 1;
  recorder.add_frame(second_map);
  RecordedFrame unknown_reference = tracked(3, 9, translation(0, 0, 0), translation(0.3, 0, 0));
  unknown_reference.map_id = 1;  // its keyframe never arrived: the odometry's map
  recorder.add_frame(unknown_reference);
  const RecordedTrajectories out = recorder.build();
  EXPECT_EQ(out.frame_maps, (std::vector<MapId>{0, 1, 1}));
  EXPECT_EQ(out.keyframe_maps, (std::vector<MapId>{0, 1}));
  write_recording(out, options);
  std::ifstream maps(options.maps_output);
  std::vector<std::string> lines;
  for (std::string line; std::getline(maps, line);) {
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  }
  EXPECT_EQ(lines, (std::vector<std::string>{"0 1.000000000 0", "2 1.100000000 1", "3 1.150000000 1",
                                             "keyframe 0 1.000000000 0", "keyframe 2 1.100000000 1"}));
  EXPECT_EQ(eval::read_trajectory(options.output).size(), 3u) << "the trajectory stays a plain TUM file";
  std::filesystem::remove_all(dir);
}

Pose3 rotation_about(const Eigen::Vector3d& axis, double angle_rad, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

// Poses in the frame the ground truth is of. Known answer: a body moving along T_Wb(t)
// in some world W carries a rectified camera at T_b_r; the tracker sees T_wr(t) = T_Wr(0)^-1 T_Wr(t)
// (world: the camera at the first keyframe). In the body frame the recorder must write the body's
// motion from its first pose, T_Wb(0)^-1 T_Wb(t); rectified leaves the poses untouched, bit for bit.
TEST(RecorderFrames, BodyFrameGivesTheBodysMotionAndRectifiedIsUntouched) {
  const Pose3 T_b_r = rotation_about({0.2, 1, 0.1}, 1.5, {-0.02, 0.065, 0.01});
  std::vector<Pose3> T_Wb;
  for (int t = 0; t < 5; ++t)
    T_Wb.push_back(rotation_about({t * 0.3, 1, 0.5}, 0.1 * t + 0.4, {1.0 + 0.2 * t, 2.0, 0.1 * t * t}));
  RecordedTrajectories recording;
  for (int t = 0; t < 5; ++t) {
    const Pose3 T_wr = (T_Wb[0] * T_b_r).inverse() * (T_Wb[t] * T_b_r);
    recording.frames.push_back(T_wr, t, 1.0 + t);
    if (t % 2 == 0) recording.keyframes.push_back(T_wr, t, 1.0 + t);
  }
  RecordedTrajectories body = recording;
  express_in_frame(body, eval::PoseFrame::body, T_b_r);
  EXPECT_EQ(body.frames.frame, eval::PoseFrame::body);
  EXPECT_EQ(body.keyframes.frame, eval::PoseFrame::body);
  for (int t = 0; t < 5; ++t) {
    const Pose3 expected = T_Wb[0].inverse() * T_Wb[t];
    EXPECT_TRUE(body.frames.poses_wc[t].matrix().isApprox(expected.matrix(), 1e-12)) << "frame " << t;
  }
  EXPECT_TRUE(body.keyframes.poses_wc[1].matrix().isApprox((T_Wb[0].inverse() * T_Wb[2]).matrix(), 1e-12));

  RecordedTrajectories rectified = recording;
  express_in_frame(rectified, eval::PoseFrame::rectified, T_b_r);
  EXPECT_EQ(rectified.frames.frame, eval::PoseFrame::rectified);
  for (int t = 0; t < 5; ++t) EXPECT_EQ(rectified.frames.poses_wc[t].matrix(), recording.frames.poses_wc[t].matrix());
}

TEST(RecorderFrames, FrameOptionDefaultsToBodyAndRejectsOthers) {
  const RecorderOptions defaults = RecorderOptions::from(runtime::Config::empty(), {});
  EXPECT_EQ(defaults.frame, eval::PoseFrame::body);
  EXPECT_FALSE(defaults.frame_given);
  const RecorderOptions cam0 = RecorderOptions::from(runtime::Config::empty(), {"--frame", "cam0"});
  EXPECT_EQ(cam0.frame, eval::PoseFrame::cam0);
  EXPECT_TRUE(cam0.frame_given);
  try {
    RecorderOptions::from(runtime::Config::empty(), {"--frame", "imu"});
    FAIL() << "--frame imu accepted";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "--frame: expected body, cam0 or rectified, got 'imu'");
  }
}

// The summary accounts for every published frame: with a pose, untracked, or never
// received (missed by the frontend, or lost on the way) — listed exactly, by seq.
TEST(RecorderSummary, AccountsForEveryPublishedFrame) {
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 0, 0, Pose3::Identity());
  for (std::uint64_t seq : {0, 1, 5}) recorder.add_frame(tracked(seq, 1, Pose3::Identity(), Pose3::Identity()));
  RecordedFrame lost;
  lost.seq = 2;
  lost.state = "LOST";
  recorder.add_frame(lost);
  const FrameAccount account = recorder.account(8);
  EXPECT_EQ(account.published, 8u);
  EXPECT_EQ(account.with_pose, 3u);
  EXPECT_EQ(account.untracked, 1u);
  EXPECT_EQ(account.never_received_count(), 4u);
  EXPECT_EQ(account.never_received_text(), "3-4, 6-7");
  EXPECT_EQ(account.without_pose(), 5u);
  EXPECT_EQ(summary_line(account, "out/run.txt"), "tracked 3/8 frames, 5 lost, trajectory out/run.txt");
  // Without the publisher's count, the highest seq stands in.
  EXPECT_EQ(recorder.account(0).published, 6u);
  EXPECT_EQ(TrajectoryRecorder().account(0).published, 0u);
}

// An output that is a folder is an error naming the file (the recorder reports it at
// start-up), and a write never leaves a half-written or temporary file behind.
TEST(RecorderFiles, FolderAsOutputIsAnErrorAndWritesAreAtomic) {
  const auto dir = std::filesystem::temp_directory_path() / ("heslam_recorder_atomic_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "taken.txt");
  TrajectoryRecorder recorder;
  recorder.add_keyframe(1, 1'000'000'000, 0, Pose3::Identity());
  recorder.add_frame(tracked(0, 1, Pose3::Identity(), Pose3::Identity()));
  RecorderOptions options = RecorderOptions::from(runtime::Config::empty(), {"--output", (dir / "taken.txt").string()});
  try {
    write_recording(recorder.build(), options);
    ADD_FAILURE() << "a folder accepted as the trajectory file";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()),
              (dir / "taken.txt").string() + ": is a folder; expected the file name of the trajectory");
  }
  options = RecorderOptions::from(runtime::Config::empty(), {"--output", (dir / "run.txt").string()});
  write_recording(recorder.build(), options);
  recorder.add_frame(tracked(1, 1, Pose3::Identity(), translation(0.1, 0, 0)));
  write_recording(recorder.build(), options);  // replaced whole
  EXPECT_EQ(eval::read_trajectory(options.output).size(), 2u);
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
  std::filesystem::remove_all(dir);
}

// Largest element difference of two poses (a plain loop: GCC 12 warns falsely on Eigen's AVX-512
// reductions here).
double max_abs_difference(const Pose3& a, const Pose3& b) {
  double largest = 0.0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) largest = std::max(largest, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  }
  return largest;
}

// The journal a killed recorder resumes from: frames come back exactly (poses bit for bit through
// %.17g), a torn last line is skipped and counted, and a journal of another run is replaced.
TEST(FrameJournal, RoundTripsFramesExactlyAndSkipsATornLine) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "heslam_frame_journal_test.journal";
  std::filesystem::remove(path);
  Pose3 rotated = translation(0.1, -0.2, 3.0);
  rotated.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  RecordedFrame lost;
  lost.seq = 3;
  lost.stamp_ns = 1'150'000'000;
  lost.state = "LOST";
  {
    FrameJournal journal(path);
    EXPECT_TRUE(journal.open_for_run("run-a").frames.empty());
    journal.append(tracked(1, 7, rotated, translation(1, 2, 3)));
    journal.append(tracked(2, 7, translation(0, 0, 0.5), rotated));
    journal.append(lost);
  }
  std::ofstream(path, std::ios::app) << "4 1200000000 1 OK 7 0.1 0.2";  // killed mid-write
  {
    FrameJournal journal(path);
    const FrameJournal::Opened opened = journal.open_for_run("run-a");
    ASSERT_EQ(opened.frames.size(), 3u);
    EXPECT_EQ(opened.torn_lines, 1);
    EXPECT_EQ(opened.frames[0].seq, 1u);
    EXPECT_EQ(opened.frames[0].reference, 7u);
    EXPECT_TRUE(opened.frames[0].tracked);
    EXPECT_LT(max_abs_difference(opened.frames[0].T_ref_c, rotated), 1e-15);
    EXPECT_LT(max_abs_difference(opened.frames[1].T_wc, rotated), 1e-15);
    EXPECT_FALSE(opened.frames[2].tracked);
    EXPECT_EQ(opened.frames[2].state, "LOST");
    EXPECT_EQ(opened.frames[2].stamp_ns, 1'150'000'000);
  }
  {
    FrameJournal journal(path);
    EXPECT_TRUE(journal.open_for_run("run-b").frames.empty());  // another run: replaced
  }
  FrameJournal journal(path);
  EXPECT_TRUE(journal.open_for_run("run-a").frames.empty());  // ... and gone for good
  journal.remove();
  EXPECT_FALSE(std::filesystem::exists(path));
}

// A new journal of run "run-a" in the temporary folder holding tracked frames 1..count, frame n at
// x = n; closed.
std::filesystem::path journal_of_tracked_frames(const std::string& name, std::uint64_t count) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove(path);
  FrameJournal journal(path);
  journal.open_for_run("run-a");
  for (std::uint64_t seq = 1; seq <= count; ++seq) {
    journal.append(tracked(seq, 7, translation(0, 0, 0), translation(static_cast<double>(seq), 0, 0)));
  }
  return path;
}

// A recorder killed mid-write, restarted, and appending again: the frame appended after the torn line
// is on a line of its own and comes back at the next open, not glued to the torn line and lost.
TEST(FrameJournal, AFrameAppendedAfterATornLineSurvivesTheNextOpen) {
  const std::filesystem::path path = journal_of_tracked_frames("heslam_frame_journal_glued.journal", 1);
  std::ofstream(path, std::ios::app) << "2 1100000000 1 OK 7 0.1 0.2";  // killed mid-write
  {
    FrameJournal journal(path);
    EXPECT_EQ(journal.open_for_run("run-a").frames.size(), 1u);
    journal.append(tracked(3, 7, translation(0, 0, 0), translation(3, 0, 0)));  // the restarted recorder
  }
  FrameJournal journal(path);
  const FrameJournal::Opened opened = journal.open_for_run("run-a");
  ASSERT_EQ(opened.frames.size(), 2u);
  EXPECT_EQ(opened.frames[1].seq, 3u);
  EXPECT_EQ(opened.frames[1].T_wc.translation().x(), 3.0);
  journal.remove();
}

// A phantom line (right format, but not what the recorder wrote) would become an extra pose and
// frames lost that never existed: it is dropped and counted, and so is a line out of sequence.
TEST(FrameJournal, APhantomLineIsDroppedAndCountedNotRecorded) {
  const std::filesystem::path path = journal_of_tracked_frames("heslam_frame_journal_phantom.journal", 2);
  const std::string phantom = "142 8100000000 1 OK 7 0 0 0 0 0 0 1 5 0 0 0 0 0 1";
  std::ofstream(path, std::ios::app) << phantom << " #3 0badf00d\n";            // a wrong checksum
  std::ofstream(path, std::ios::app) << runtime::RunJournal::line(2, phantom);  // a number used before
  FrameJournal journal(path);
  const FrameJournal::Opened opened = journal.open_for_run("run-a");
  ASSERT_EQ(opened.frames.size(), 2u);
  EXPECT_EQ(opened.frames[1].seq, 2u);
  EXPECT_EQ(opened.dropped_lines, 2);
  EXPECT_EQ(opened.dropped_report,
            path.string() + ": 2 lines dropped, not resumed from (1 failing their checksum, 1 out of sequence)");
  journal.remove();
}

}  // namespace
}  // namespace heslam::recorder
