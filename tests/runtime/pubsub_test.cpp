// In-process message round trips over a real DDS domain (own id per test): content equality,
// sample ownership (run under ASan), keyed state with disposes, transient-local late joiners,
// schema-version rejection, WaitSet timeouts.
#include <chrono>
#include <numeric>
#include <thread>

#include <gtest/gtest.h>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/run_id.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "runtime/waitset.hpp"
#include "runtime/writer.hpp"
#include "runtime/writer_identity.hpp"
#include "test_domain.hpp"

namespace heslam::runtime {
namespace {

using namespace std::chrono_literals;

// Discovery + delivery on loopback take milliseconds; this only bounds a broken run.
constexpr auto kDeadline = 5s;

template <typename T>
std::optional<Received<T>> take_within(Reader<T>& reader, Participant& participant) {
  WaitSet waitset(participant);
  waitset.attach(reader);
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (std::chrono::steady_clock::now() < deadline) {
    if (auto received = reader.take_one()) return received;
    waitset.wait(100ms);
  }
  return std::nullopt;
}

class PubSub : public ::testing::Test {
 protected:
  Participant participant{ParticipantOptions{test::test_domain_id(), ""}};
  Topics topics{"pubsubtest_" + std::to_string(getpid())};  // own names even on a shared domain
};

TEST_F(PubSub, StereoFrameArrivesByteExact) {
  Writer<msg::StereoFrame> writer(participant, topics.stereo());
  Reader<msg::StereoFrame> reader(participant, topics.stereo());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));

  constexpr uint32_t kWidth = 752, kHeight = 480;
  std::vector<uint8_t> left(kWidth * kHeight), right(kWidth * kHeight);
  std::iota(left.begin(), left.end(), uint8_t{0});
  std::iota(right.begin(), right.end(), uint8_t{7});
  msg::StereoFrame frame{};
  frame.stamp_ns = 1403715273262142976;
  frame.stamp_right_ns = frame.stamp_ns;
  frame.seq = 42;
  frame.width_px = kWidth;
  frame.height_px = kHeight;
  frame.encoding = heslam_msg_ENCODING_MONO8;
  borrow(frame.left, left);
  borrow(frame.right, right);
  ASSERT_EQ(writer.write(frame), WriteResult::kOk);

  auto received = take_within(reader, participant);
  ASSERT_TRUE(received);
  EXPECT_TRUE(received->info.valid_data);
  const msg::StereoFrame& got = *received->sample;
  EXPECT_EQ(got.schema_version, msg::kSchemaVersion);
  EXPECT_EQ(got.stamp_ns, 1403715273262142976);
  EXPECT_EQ(got.seq, 42u);
  EXPECT_EQ(got.width_px, kWidth);
  const auto got_left = view(got.left);
  const auto got_right = view(got.right);
  EXPECT_TRUE(std::equal(got_left.begin(), got_left.end(), left.begin(), left.end()));
  EXPECT_TRUE(std::equal(got_right.begin(), got_right.end(), right.begin(), right.end()));
}

// take_into: one Received reused for a stream of frames whose sizes grow, shrink and vanish; every
// frame arrives exact, and a frame no larger than the buffer is taken without a new allocation.
TEST_F(PubSub, TakeIntoReusesTheSampleBuffersAndStaysExact) {
  Writer<msg::StereoFrame> writer(participant, topics.stereo(), Qos(QosRole::kImages).keep_last(8));
  Reader<msg::StereoFrame> reader(participant, topics.stereo(), Qos(QosRole::kImages).keep_last(8));
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));
  const std::vector<uint32_t> widths{752, 752, 1241, 320, 0, 752};  // height 4 rows each
  for (std::size_t k = 0; k < widths.size(); ++k) {
    std::vector<uint8_t> left(widths[k] * 4), right(widths[k] * 4);
    std::iota(left.begin(), left.end(), static_cast<uint8_t>(k));
    std::iota(right.begin(), right.end(), static_cast<uint8_t>(3 * k + 1));
    msg::StereoFrame frame{};
    frame.seq = k;
    frame.width_px = widths[k];
    frame.height_px = 4;
    frame.encoding = heslam_msg_ENCODING_MONO8;
    borrow(frame.left, left);
    borrow(frame.right, right);
    ASSERT_EQ(writer.write(frame), WriteResult::kOk);
  }
  Received<msg::StereoFrame> received;
  WaitSet waitset(participant);
  waitset.attach(reader);
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  const uint8_t* previous_buffer = nullptr;
  uint32_t previous_capacity = 0;
  for (std::size_t k = 0; k < widths.size(); ++k) {
    while (!reader.take_into(received) && std::chrono::steady_clock::now() < deadline) waitset.wait(100ms);
    ASSERT_TRUE(received.info.valid_data) << "frame " << k;
    const msg::StereoFrame& got = *received.sample;
    ASSERT_EQ(got.seq, k);
    ASSERT_EQ(got.left._length, widths[k] * 4) << "frame " << k;
    for (uint32_t i = 0; i < got.left._length; ++i) {
      ASSERT_EQ(got.left._buffer[i], static_cast<uint8_t>(k + i)) << "frame " << k << " byte " << i;
      ASSERT_EQ(got.right._buffer[i], static_cast<uint8_t>(3 * k + 1 + i)) << "frame " << k << " byte " << i;
    }
    if (previous_buffer != nullptr && got.left._length > 0 && got.left._length <= previous_capacity) {
      EXPECT_EQ(got.left._buffer, previous_buffer) << "frame " << k << ": reallocated although it fitted";
    }
    if (got.left._buffer != nullptr) {
      previous_buffer = got.left._buffer;
      previous_capacity = std::max(previous_capacity, got.left._maximum);
    }
  }
  EXPECT_FALSE(reader.take_into(received));
}

TEST_F(PubSub, KeyframeWithNestedSequencesRoundTrips) {
  Writer<msg::Keyframe> writer(participant, topics.keyframes());
  Reader<msg::Keyframe> reader(participant, topics.keyframes());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));

  constexpr int kKeypoints = 1500;
  std::vector<msg::KeyframeKeypoint> keypoints(kKeypoints);
  std::vector<uint8_t> descriptors(kKeypoints * 32);
  std::vector<uint64_t> point_ids(kKeypoints);
  for (int i = 0; i < kKeypoints; ++i) {
    keypoints[i] = {float(i), float(2 * i), float(i) - 10.f, 1.5f + float(i), 90.f, i % 8};
    point_ids[i] = i % 3 == 0 ? 0 : (uint64_t{2} << 56) + uint64_t(i);
  }
  std::iota(descriptors.begin(), descriptors.end(), uint8_t{3});
  std::vector<msg::NewStereoPoint> new_points{{(uint64_t{1} << 56) + 5, 5, {1.0, 2.0, 3.0}}};
  msg::Keyframe keyframe{};
  keyframe.id = (uint64_t{1} << 56) + 1;
  keyframe.stamp_ns = 123;
  keyframe.T_wc = msg::Pose{{1, 2, 3}, {0, 0, 0.6, 0.8}};
  keyframe.camera = msg::RectifiedStereoCamera{435.2, 435.2, 367.4, 252.2, 0.11, 752, 480};
  keyframe.pyramid_levels = 8;
  keyframe.scale_factor = 1.2f;
  borrow(keyframe.keypoints, keypoints);
  borrow(keyframe.descriptors, descriptors);
  borrow(keyframe.point_ids, point_ids);
  borrow(keyframe.new_points, new_points);
  ASSERT_EQ(writer.write(keyframe), WriteResult::kOk);

  auto received = take_within(reader, participant);
  ASSERT_TRUE(received);
  const msg::Keyframe& got = *received->sample;
  EXPECT_EQ(got.id, keyframe.id);
  EXPECT_DOUBLE_EQ(got.T_wc.orientation_xyzw[3], 0.8);
  EXPECT_DOUBLE_EQ(got.camera.baseline_m, 0.11);
  ASSERT_EQ(view(got.keypoints).size(), size_t{kKeypoints});
  EXPECT_FLOAT_EQ(view(got.keypoints)[1499].v_px, 2998.f);
  EXPECT_EQ(view(got.keypoints)[1499].octave, 1499 % 8);
  const auto got_descriptors = view(got.descriptors);
  EXPECT_TRUE(std::equal(got_descriptors.begin(), got_descriptors.end(), descriptors.begin(), descriptors.end()));
  const auto got_ids = view(got.point_ids);
  EXPECT_TRUE(std::equal(got_ids.begin(), got_ids.end(), point_ids.begin(), point_ids.end()));
  ASSERT_EQ(view(got.new_points).size(), 1u);
  EXPECT_DOUBLE_EQ(view(got.new_points)[0].position_w_m[2], 3.0);
}

TEST_F(PubSub, StringsAndStatusRoundTrip) {
  Writer<msg::ComponentStatus> writer(participant, topics.status());
  Reader<msg::ComponentStatus> reader(participant, topics.status());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));
  const std::string name = "frontend", executable = "/bin/heslam-frontend", counter = "frames";
  std::vector<msg::Counter> counters{{borrow(counter), 17}};
  msg::ComponentStatus status{};
  status.name = borrow(name);
  status.executable = borrow(executable);
  status.pid = 99;
  status.state = heslam_msg_STATE_RUNNING;
  borrow(status.counters, counters);
  std::string empty;  // empty strings must survive too
  status.message = borrow(empty);
  // Status is best effort; repeat until one arrives (bounded).
  std::optional<Received<msg::ComponentStatus>> received;
  for (int attempt = 0; attempt < 50 && !received; ++attempt) {
    writer.write(status);
    WaitSet waitset(participant);
    waitset.attach(reader);
    waitset.wait(100ms);
    received = reader.take_one();
  }
  ASSERT_TRUE(received);
  EXPECT_EQ(to_string(received->sample->name), "frontend");
  EXPECT_EQ(to_string(received->sample->executable), "/bin/heslam-frontend");
  EXPECT_EQ(to_string(received->sample->message), "");
  ASSERT_EQ(view(received->sample->counters).size(), 1u);
  EXPECT_EQ(to_string(view(received->sample->counters)[0].name), "frames");
  EXPECT_EQ(view(received->sample->counters)[0].value, 17u);
}

TEST_F(PubSub, LateJoinerGetsEveryKeyframeAndDisposesArrive) {
  Writer<msg::KeyframeState> writer(participant, topics.keyframe_states());
  constexpr uint64_t kKeyframes = 50;
  for (uint64_t id = 1; id <= kKeyframes; ++id) {
    msg::KeyframeState state{};
    state.id = id;
    state.map_version = 1;
    ASSERT_EQ(writer.write(state), WriteResult::kOk);
  }
  for (uint64_t id = 1; id <= kKeyframes; ++id) {  // a second version of each: only the last is kept
    msg::KeyframeState state{};
    state.id = id;
    state.map_version = 2;
    writer.write(state);
  }
  Reader<msg::KeyframeState> late(participant, topics.keyframe_states());
  std::map<uint64_t, uint64_t> versions;
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (versions.size() < kKeyframes && std::chrono::steady_clock::now() < deadline) {
    for (auto& received : late.take()) versions[received.sample->id] = received.sample->map_version;
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_EQ(versions.size(), kKeyframes);
  for (const auto& [id, version] : versions) EXPECT_EQ(version, 2u) << id;

  msg::KeyframeState culled{};
  culled.id = 7;
  writer.dispose(culled);
  auto notice = take_within(late, participant);
  ASSERT_TRUE(notice);
  EXPECT_FALSE(notice->info.valid_data);
  EXPECT_TRUE(notice->info.disposed);
  EXPECT_EQ(notice->sample->id, 7u);  // the key is filled in on invalid samples
}

// A lockstep consumer can write its first ack before its writer has matched the publisher's ack
// reader (discovery matches each direction on its own); the ack must still arrive.
TEST_F(PubSub, LockstepAckWrittenBeforeTheReaderExistsArrives) {
  Writer<msg::FrameDone> writer(participant, topics.frame_done());
  for (uint64_t seq = 0; seq < 3; ++seq) {
    msg::FrameDone done{};
    done.seq = seq;
    ASSERT_EQ(writer.write(done), WriteResult::kOk);
  }
  Reader<msg::FrameDone> late(participant, topics.frame_done());
  std::vector<uint64_t> seqs;
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (seqs.size() < 3 && std::chrono::steady_clock::now() < deadline) {
    for (auto& received : late.take()) seqs.push_back(received.sample->seq);
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(seqs, (std::vector<uint64_t>{0, 1, 2}));
}

// has_unread: true while a sample waits, without consuming it (the real-time mapper's BA asks it
// every iteration; the keyframe must still be there to take afterwards).
TEST_F(PubSub, HasUnreadSeesAWaitingSampleWithoutTakingIt) {
  Writer<msg::KeyframeDone> writer(participant, topics.keyframe_done());
  Reader<msg::KeyframeDone> reader(participant, topics.keyframe_done());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));
  EXPECT_FALSE(reader.has_unread());
  msg::KeyframeDone done{};
  done.keyframe_id = 42;
  ASSERT_EQ(writer.write(done), WriteResult::kOk);
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (!reader.has_unread() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(1ms);
  ASSERT_TRUE(reader.has_unread());
  EXPECT_TRUE(reader.has_unread());  // asking again does not consume it
  auto received = reader.take_one();
  ASSERT_TRUE(received);
  EXPECT_EQ(received->sample->keyframe_id, 42u);
  EXPECT_FALSE(reader.has_unread());
}

TEST_F(PubSub, SampleFromAnotherSchemaIsDroppedAndCounted) {
  Writer<msg::FrameDone> writer(participant, topics.frame_done());
  Reader<msg::FrameDone> reader(participant, topics.frame_done());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));
  msg::FrameDone foreign{};
  foreign.schema_version = msg::kSchemaVersion + 1;
  foreign.seq = 1;
  std::string component = "other-build";
  foreign.component = borrow(component);
  ASSERT_EQ(dds_write(writer.handle(), &foreign), DDS_RETCODE_OK);  // raw: bypasses the stamping
  msg::FrameDone ours{};
  ours.seq = 2;
  ours.component = borrow(component);
  writer.write(ours);
  auto received = take_within(reader, participant);
  ASSERT_TRUE(received);
  EXPECT_EQ(received->sample->seq, 2u);
  EXPECT_EQ(reader.schema_mismatches(), 1u);
  EXPECT_EQ(schema_mismatch_message("heslam/x", 9),
            "topic 'heslam/x': dropped a sample with message schema version 9, this build has version " +
                std::to_string(msg::kSchemaVersion) + " (rebuild every heslam process from the same tree)");
}

TEST_F(PubSub, WaitSetTimesOutWithoutDataAndWakesOnRequest) {
  Reader<msg::Odometry> reader(participant, topics.odometry());
  WaitSet waitset(participant);
  waitset.attach(reader);
  EXPECT_EQ(waitset.wait(20ms), Wake::kTimeout);
  waitset.wake();
  EXPECT_EQ(waitset.wait(kDeadline), Wake::kWoken);
  EXPECT_EQ(waitset.wait(20ms), Wake::kTimeout);  // the wake was consumed
}

TEST_F(PubSub, TwoParticipantsShareOneDomainInAProcess) {
  Participant second(ParticipantOptions{test::test_domain_id(), ""});
  Writer<msg::KeyframeDone> writer(second, topics.keyframe_done());
  Reader<msg::KeyframeDone> reader(participant, topics.keyframe_done());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));
  msg::KeyframeDone done{};
  done.keyframe_id = 5;
  std::string component = "mapper";
  done.component = borrow(component);
  writer.write(done);
  auto received = take_within(reader, participant);
  ASSERT_TRUE(received);
  EXPECT_EQ(received->sample->keyframe_id, 5u);
  EXPECT_EQ(to_string(received->sample->component), "mapper");
}

TEST(Topics, NamesLiveUnderTheNamespace) {
  EXPECT_EQ(Topics().stereo().name, "heslam/camera/stereo");
  EXPECT_EQ(Topics("robot1").map_points().name, "robot1/map/points");
  EXPECT_EQ(Topics("a/b").status().role, QosRole::kStatus);
  EXPECT_EQ(all_topics().size(), 18u);
}

TEST(Participant, BadDomainIsOneLine) {
  try {
    Participant participant(ParticipantOptions{300, ""});
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "DDS domain 300: expected an id in [0, 232]");
  }
}

// The last acknowledgement of a process that exits (lockstep/frame_done, .../keyframe_done) is
// taken after its writer left, when the run it advertised can no longer be asked: a writer known
// while it was matched is still of this run then (writer_identity.hpp).
TEST_F(PubSub, AWriterKnownWhileMatchedStaysOfThisRunAfterItLeft) {
  setenv(kRunOnOneHostVariable, "1", 1);
  Reader<msg::FrameDone> reader(participant, topics.frame_done());
  std::optional<Writer<msg::FrameDone>> writer(std::in_place, participant, topics.frame_done());
  ASSERT_TRUE(writer->wait_for_readers(1, kDeadline));
  msg::FrameDone done{};
  done.seq = 1;
  std::string component = "test";
  done.component = borrow(component);
  writer->write(done);
  const auto first = take_within(reader, participant);
  ASSERT_TRUE(first);
  const dds_instance_handle_t publication = first->info.publication_handle;
  EXPECT_TRUE(writer_of_this_run(reader.handle(), publication));

  done.seq = 2;
  writer->write(done);
  writer.reset();
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (writer_matched(reader.handle(), publication) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(10ms);
  ASSERT_FALSE(writer_matched(reader.handle(), publication)) << "the writer never left";
  std::optional<Received<msg::FrameDone>> second;
  while (!second && std::chrono::steady_clock::now() < deadline) {
    second = take_within(reader, participant);
    if (second && !second->info.valid_data) second.reset();
  }
  ASSERT_TRUE(second) << "the sample written before the writer left was not delivered";
  EXPECT_EQ(second->sample->seq, 2u);
  EXPECT_TRUE(writer_of_this_run(reader.handle(), second->info.publication_handle));
  unsetenv(kRunOnOneHostVariable);
}

}  // namespace
}  // namespace heslam::runtime
