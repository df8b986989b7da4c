// The frontend's journal (OdometryJournal): what a restarted frontend resumes from. Frames come back
// exactly, a torn last line is skipped and the next append starts on a line of its own, a journal of
// another run is replaced, a forged line (well formed, but not what the frontend wrote) is dropped.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "components/frontend/odometry_journal.hpp"
#include "runtime/run_journal.hpp"

namespace heslam::frontend {
namespace {

msg::Odometry odometry(std::uint64_t seq, heslam_msg_TrackingState state, double x) {
  msg::Odometry message{};
  message.seq = seq;
  message.stamp_ns = 1'000'000'000 + static_cast<std::int64_t>(seq) * 50'000'000;
  message.state = state;
  message.reference_keyframe_id = (std::uint64_t{1} << 56) | (seq / 10);
  message.T_wc = msg::Pose{{x, 0.1 / 3.0, -2.0}, {0.0, 0.0, 0.0, 1.0}};
  message.T_ref_c = msg::Pose{{0.5, 1.0 / 7.0, 0.0}, {0.6, 0.0, 0.0, 0.8}};
  message.keypoints = 1200;
  message.tracked_points = 300 + static_cast<std::uint32_t>(seq);
  message.keyframe_created = seq % 10 == 0;
  message.map_id = static_cast<std::uint32_t>(seq % 3);  // the atlas: the map each frame was in
  return message;
}

TEST(OdometryJournal, ResumesTheFramesOfItsRunExactlyAndSurvivesATornLine) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "heslam_odometry_journal_test.frontend";
  std::filesystem::remove(path);
  {
    OdometryJournal journal(path);
    EXPECT_FALSE(journal.open_for_run("run-a").last_seq);
    journal.append(odometry(0, heslam_msg_TRACKING_OK, 1.0 / 3.0), false);  // a keyframe's frame, published
    journal.append(odometry(0, heslam_msg_TRACKING_OK, 1.0 / 3.0), true);   // ... and finished
    journal.append(odometry(1, heslam_msg_TRACKING_LOST, 0.0), true);
  }
  std::ofstream(path, std::ios::app) << "2 1100000000 0 7 0.1";  // killed mid-write
  {
    OdometryJournal journal(path);
    const OdometryJournal::Opened opened = journal.open_for_run("run-a");
    ASSERT_EQ(opened.frames.size(), 2u);  // one per seq
    EXPECT_EQ(opened.torn_lines, 1);
    EXPECT_EQ(opened.last_seq, 1u);
    const msg::Odometry expected = odometry(0, heslam_msg_TRACKING_OK, 1.0 / 3.0);
    const msg::Odometry& first = opened.frames[0];
    EXPECT_EQ(first.stamp_ns, expected.stamp_ns);
    EXPECT_EQ(first.state, heslam_msg_TRACKING_OK);
    EXPECT_EQ(first.reference_keyframe_id, expected.reference_keyframe_id);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(first.T_wc.position_m[i], expected.T_wc.position_m[i]);  // bit for bit (%.17g)
      EXPECT_EQ(first.T_ref_c.position_m[i], expected.T_ref_c.position_m[i]);
    }
    EXPECT_EQ(first.T_ref_c.orientation_xyzw[0], 0.6);
    EXPECT_EQ(first.tracked_points, 300u);
    EXPECT_TRUE(first.keyframe_created);
    EXPECT_EQ(first.map_id, 0u);
    EXPECT_EQ(opened.frames[1].map_id, 1u);
    EXPECT_EQ(opened.frames[1].state, heslam_msg_TRACKING_LOST);
    journal.append(odometry(2, heslam_msg_TRACKING_OK, 2.0), true);   // after the torn line, not glued to it
    journal.append(odometry(3, heslam_msg_TRACKING_OK, 3.0), false);  // killed while waiting for the mapper
  }
  {
    OdometryJournal journal(path);
    const OdometryJournal::Opened opened = journal.open_for_run("run-a");
    ASSERT_EQ(opened.frames.size(), 4u);  // the unfinished frame's odometry too (its keyframe) ...
    EXPECT_EQ(opened.frames[3].seq, 3u);
    EXPECT_EQ(opened.torn_lines, 0);  // cut off by the open before
    EXPECT_EQ(opened.last_seq, 2u);   // ... but it is tracked again
  }
  {
    OdometryJournal journal(path);
    EXPECT_TRUE(journal.open_for_run("run-b").frames.empty());  // another run: replaced
  }
  OdometryJournal journal(path);
  EXPECT_TRUE(journal.open_for_run("run-a").frames.empty());  // ... and gone for good
  journal.remove();
  EXPECT_FALSE(std::filesystem::exists(path));
}

// A line whose state is no TrackingState (a damaged file) is skipped and counted like a torn one:
// it is never turned into the enum (undefined for such a value; runtime/wire_enum.hpp).
TEST(OdometryJournal, ALineWithAnUnknownStateIsSkipped) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "heslam_odometry_journal_state.frontend";
  std::filesystem::remove(path);
  {
    OdometryJournal journal(path);
    journal.open_for_run("run-a");
    journal.append(odometry(0, heslam_msg_TRACKING_OK, 1.0), true);
    journal.append(odometry(1, heslam_msg_TRACKING_OK, 2.0), true);
  }
  std::stringstream text;
  text << std::ifstream(path).rdbuf();
  std::string content = text.str();
  const std::size_t last = content.rfind('\n', content.size() - 2) + 1;             // the start of seq 1's line
  const std::size_t state_at = content.find(' ', content.find(' ', last) + 1) + 1;  // its third field
  ASSERT_EQ(content.substr(last, 2), "1 ");
  ASSERT_EQ(content[state_at], '1');  // TRACKING_OK
  content[state_at] = '7';
  // With its checksum made right again: the line passes the journal, and the state is what fails.
  std::string record = content.substr(last, content.rfind(" #") - last);
  content = content.substr(0, last) + runtime::RunJournal::line(2, record);
  std::ofstream(path, std::ios::trunc) << content;
  OdometryJournal journal(path);
  const OdometryJournal::Opened opened = journal.open_for_run("run-a");
  ASSERT_EQ(opened.frames.size(), 1u);
  EXPECT_EQ(opened.frames[0].seq, 0u);
  EXPECT_EQ(opened.torn_lines, 1);
  journal.remove();
}

// A well-formed line that is not what the frontend wrote (a pose metres off, a frame it never
// finished) is never resumed from: it would be acknowledged without tracking. The frames after it
// are dropped too (what they record followed the frame it replaced); each drop is counted.
TEST(OdometryJournal, AForgedLineIsDroppedAndCountedNotResumedFrom) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "heslam_odometry_journal_forged.frontend";
  std::filesystem::remove(path);
  {
    OdometryJournal journal(path);
    journal.open_for_run("run-a");
    for (std::uint64_t seq = 0; seq < 3; ++seq) journal.append(odometry(seq, heslam_msg_TRACKING_OK, 1.0), true);
  }
  std::stringstream text;
  text << std::ifstream(path).rdbuf();
  std::string content = text.str();
  std::size_t x_at = content.find("\n1 ") + 1;                                 // seq 1's line
  for (int field = 0; field < 4; ++field) x_at = content.find(' ', x_at) + 1;  // seq stamp state reference
  ASSERT_EQ(content.substr(x_at, 2), "1 ");                                    // T_wc's x
  content.replace(x_at, 1, "9.7");                                             // right format, wrong checksum
  std::ofstream(path, std::ios::trunc) << content;
  {
    OdometryJournal journal(path);
    const OdometryJournal::Opened opened = journal.open_for_run("run-a");
    ASSERT_EQ(opened.frames.size(), 1u);
    EXPECT_EQ(opened.frames[0].T_wc.position_m[0], 1.0);
    EXPECT_EQ(opened.last_seq, 0u);  // frames 1 and 2 are tracked again
    EXPECT_EQ(opened.dropped_lines, 2);
    EXPECT_EQ(opened.torn_lines, 0);
    EXPECT_EQ(opened.dropped_report,
              path.string() + ": 2 lines dropped, not resumed from (1 failing their checksum, 1 out of sequence)");
    journal.append(odometry(1, heslam_msg_TRACKING_OK, 1.0), true);
  }
  // A line with a right checksum but a number already used (a line copied, or another writer).
  std::ofstream(path, std::ios::app) << runtime::RunJournal::line(2,
                                                                  "5 1250000000 1 72057594037927936 8.7 0 0 0 0 0 1 "
                                                                  "0 0 0 0 0 0 1 1200 305 0 1");
  OdometryJournal journal(path);
  const OdometryJournal::Opened opened = journal.open_for_run("run-a");
  ASSERT_EQ(opened.frames.size(), 2u);
  EXPECT_EQ(opened.last_seq, 1u);
  EXPECT_EQ(opened.dropped_lines, 1);
  journal.remove();
}

TEST(OdometryJournal, UnwritablePathThrowsNamingTheFile) {
  OdometryJournal journal("/proc/heslam_no_such_dir/x.frontend");
  try {
    journal.open_for_run("run-a");
    FAIL() << "expected an error";
  } catch (const std::exception& error) {
    EXPECT_NE(std::string(error.what()).find("/proc/heslam_no_such_dir/x.frontend"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace heslam::frontend
