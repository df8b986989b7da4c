// CheckedReader: validation with a counted, rate-limited warning, the first
// writer owning the stream, a second writer's samples held and ignored while the first is alive, and
// its take-over (held samples first, in order) once the first writer is gone — the restarted-publisher
// case — only by a writer of the owner's run: a writer of another run never gets a sample through,
// whether the owner left cleanly (the end of a run) or crashed (kill -9 of a writer process, then the
// lease). Writers sit in their own participants, as other processes would; the runs are set
// explicitly (Qos::run_identity), all of this process's writers being of one run otherwise.
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "child_process.hpp"
#include "runtime/checked_reader.hpp"
#include "runtime/participant.hpp"
#include "runtime/role_binding.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "runtime/writer_identity.hpp"
#include "test_domain.hpp"

namespace heslam::runtime {
namespace {

using namespace std::chrono_literals;

// Discovery + delivery on loopback take milliseconds; this only bounds a broken run.
constexpr auto kDeadline = 5s;
// A killed writer stays matched until its lease (2 s, config/cyclonedds.xml) expires: the bound of
// a take-over after a crash, with room for a loaded machine.
constexpr auto kCrashDeadline = 15s;
// A run id other than this process's (another supervisor, a tool started by hand).
constexpr const char* kOtherRun = "4242:1";

std::optional<std::string> finite_pose(const msg::Odometry& odometry) {
  if (std::isfinite(odometry.T_wc.position_m[0])) return std::nullopt;
  return std::string("T_wc.position_m[0] is not finite");
}

msg::Odometry odometry(std::uint64_t seq, double x_m) {
  msg::Odometry sample{};
  sample.seq = seq;
  sample.T_wc.position_m[0] = x_m;
  sample.T_wc.orientation_xyzw[3] = 1.0;
  return sample;
}

class CheckedReaderTest : public ::testing::Test {
 protected:
  Participant make_participant() { return Participant(ParticipantOptions{test::test_domain_id(), ""}); }

  CheckedReaderOptions options() {
    CheckedReaderOptions result;
    result.rejected_counter = "rejected_odometry";
    return result;
  }

  // Seqs taken until `count` arrived or the deadline passed.
  std::vector<std::uint64_t> take_seqs(CheckedReader<msg::Odometry>& reader, std::size_t count) {
    std::vector<std::uint64_t> seqs;
    const auto deadline = std::chrono::steady_clock::now() + kDeadline;
    while (seqs.size() < count && std::chrono::steady_clock::now() < deadline) {
      for (auto& received : reader.take()) {
        if (received.info.valid_data) seqs.push_back(received.sample->seq);
      }
      std::this_thread::sleep_for(5ms);
    }
    return seqs;
  }

  // Seqs handed out while taking until the counter `name` reached `value` (or the deadline passed):
  // what a second writer sent has arrived and was refused or held by then.
  std::vector<std::uint64_t> take_until_counted(CheckedReader<msg::Odometry>& reader, const std::string& name,
                                                std::uint64_t value) {
    std::vector<std::uint64_t> seqs;
    const auto deadline = std::chrono::steady_clock::now() + kDeadline;
    while (counter(name) < value && std::chrono::steady_clock::now() < deadline) {
      for (auto& received : reader.take()) {
        if (received.info.valid_data) seqs.push_back(received.sample->seq);
      }
      std::this_thread::sleep_for(5ms);
    }
    EXPECT_EQ(counter(name), value) << name;
    return seqs;
  }

  std::uint64_t counter(const std::string& name) const {
    const auto counters = stats.counters();
    return counters.count(name) != 0 ? counters.at(name) : 0;
  }

  // A writer of `run` in `participant`.
  Writer<msg::Odometry> writer_of_run(const Participant& participant, const std::string& run) {
    return Writer<msg::Odometry>(participant, topics.odometry(), Qos(QosRole::kOdometry).run_identity(run));
  }

  std::string topic_namespace = "checkedreadertest_" + std::to_string(getpid());
  Topics topics{topic_namespace};
  Logger log{"test"};
  Stats stats;
};

TEST_F(CheckedReaderTest, InvalidSamplesAreDroppedAndCounted) {
  Participant reading = make_participant();
  Participant writing = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> writer(writing, topics.odometry());
  ASSERT_TRUE(writer.wait_for_readers(1, kDeadline));
  writer.write(odometry(0, 1.0));
  writer.write(odometry(1, std::nan("")));
  writer.write(odometry(2, 2.0));
  EXPECT_EQ(take_seqs(reader, 2), (std::vector<std::uint64_t>{0, 2}));
  EXPECT_EQ(counter("rejected_odometry"), 1u);
  EXPECT_EQ(counter(kSecondWriterSamples), 0u);
}

TEST_F(CheckedReaderTest, ASecondWriterIsIgnoredWhileTheFirstIsAlive) {
  Participant reading = make_participant();
  Participant first_participant = make_participant();
  Participant second_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> first(first_participant, topics.odometry());
  Writer<msg::Odometry> second(second_participant, topics.odometry());
  ASSERT_TRUE(first.wait_for_readers(1, kDeadline));
  ASSERT_TRUE(second.wait_for_readers(1, kDeadline));
  first.write(odometry(0, 1.0));
  ASSERT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{0}));
  second.write(odometry(1'000'000, 1.0));  // a stray sample with a high seq
  second.write(odometry(1'000'001, 1.0));
  // Nothing of it comes out (taken until both were counted: no timing involved).
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 2).empty());
  first.write(odometry(1, 1.0));
  // Only the first writer's sample comes out.
  EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{1}));
  EXPECT_EQ(counter(kSecondWriterSamples), 2u);
  EXPECT_EQ(counter("second_writers"), 1u);
}

// Both writers are of this run (a forger that copied the run id) and both write:
// the owner wrote again while the second was alive, a conflict the run fails on (counted per topic).
TEST_F(CheckedReaderTest, TwoLiveWritersOfTheSameRunAreAConflict) {
  Participant reading = make_participant();
  Participant first_participant = make_participant();
  Participant second_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> first(first_participant, topics.odometry());
  Writer<msg::Odometry> second(second_participant, topics.odometry());
  ASSERT_TRUE(first.wait_for_readers(1, kDeadline));
  ASSERT_TRUE(second.wait_for_readers(1, kDeadline));
  first.write(odometry(0, 1.0));
  ASSERT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{0}));
  second.write(odometry(1, 100.0));
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 1).empty());
  EXPECT_EQ(counter(kWriterConflicts), 0u);  // held: could still be a restart
  first.write(odometry(1, 1.0));
  EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{1}));
  EXPECT_EQ(counter(kWriterConflicts), 1u);
  EXPECT_EQ(counter(std::string(kWriterConflictsOn) + topics.odometry().name), 1u);
  second.write(odometry(2, 100.0));  // refused from now on, never held for a take-over
  first.write(odometry(2, 1.0));
  EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{2}));
  EXPECT_EQ(counter(kWriterConflicts), 1u);
}

TEST_F(CheckedReaderTest, ASecondWriterTakesOverWhenTheFirstLeaves) {
  Participant reading = make_participant();
  Participant second_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> second(second_participant, topics.odometry());
  {
    Participant first_participant = make_participant();
    Writer<msg::Odometry> first(first_participant, topics.odometry());
    ASSERT_TRUE(first.wait_for_readers(1, kDeadline));
    ASSERT_TRUE(second.wait_for_readers(1, kDeadline));
    first.write(odometry(0, 1.0));
    ASSERT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{0}));
    // A restarted publisher whose first samples arrive while the dead one still counts as matched.
    second.write(odometry(0, 1.0));
    second.write(odometry(1, 1.0));
    EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 2).empty());  // held
  }                                                                            // the first writer is deleted
  second.write(odometry(2, 1.0));
  // Held samples first, in order, then the new ones.
  EXPECT_EQ(take_seqs(reader, 3), (std::vector<std::uint64_t>{0, 1, 2}));
}

TEST_F(CheckedReaderTest, HeldSamplesAreReleasedWithoutANewSampleOnceTheFirstWriterLeft) {
  Participant reading = make_participant();
  Participant second_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> second(second_participant, topics.odometry());
  {
    Participant first_participant = make_participant();
    Writer<msg::Odometry> first(first_participant, topics.odometry());
    ASSERT_TRUE(first.wait_for_readers(1, kDeadline));
    ASSERT_TRUE(second.wait_for_readers(1, kDeadline));
    first.write(odometry(0, 1.0));
    ASSERT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{0}));
    second.write(odometry(5, 1.0));
    EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 1).empty());  // held
  }
  // A lockstep publisher sends one frame and waits: nothing new arrives to trigger the take-over.
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (!reader.has_unread() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{5}));
}

TEST_F(CheckedReaderTest, WritersAdvertiseTheirRun) {
  Participant reading = make_participant();
  Participant writing = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> plain(writing, topics.odometry());
  Writer<msg::Odometry> other = writer_of_run(writing, kOtherRun);
  ASSERT_TRUE(plain.wait_for_readers(1, kDeadline));
  ASSERT_TRUE(other.wait_for_readers(1, kDeadline));
  plain.write(odometry(0, 1.0));
  ASSERT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{0}));
  other.write(odometry(1, 1.0));
  // The other run's sample is dropped on arrival, never handed out.
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 1).empty());
  EXPECT_EQ(counter(kOtherRunWriters), 1u);
  EXPECT_EQ(writer_run_id(reader.handle(), reader.owner()), process_run_id());
  EXPECT_EQ(writer_run_id(reader.handle(), 0), std::nullopt);  // not a matched writer
}

// A run on one host (heslam-supervisor sets HESLAM_RUN_ON_ONE_HOST): a writer of another run never
// owns the stream, even when it writes before the run's own writer (another run on the domain, a
// restarted reader that hears it first). Before: the first writer owned it whatever its run, so a
// second run's recorder recorded the first run's trajectory.
TEST_F(CheckedReaderTest, InARunOnOneHostAWriterOfAnotherRunNeverOwnsEvenWhenItWritesFirst) {
  ASSERT_EQ(setenv(kRunOnOneHostVariable, "1", 1), 0);
  struct Unset {
    ~Unset() { unsetenv(kRunOnOneHostVariable); }
  } unset;
  Participant reading = make_participant();
  Participant other_participant = make_participant();
  Participant own_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> other = writer_of_run(other_participant, kOtherRun);
  Writer<msg::Odometry> own(own_participant, topics.odometry());
  ASSERT_TRUE(other.wait_for_readers(1, kDeadline));
  ASSERT_TRUE(own.wait_for_readers(1, kDeadline));
  other.write(odometry(0, 9.0));
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 1).empty());
  own.write(odometry(0, 1.0));
  own.write(odometry(1, 1.0));
  EXPECT_EQ(take_seqs(reader, 2), (std::vector<std::uint64_t>{0, 1}));
  other.write(odometry(2, 9.0));
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 2).empty());
  EXPECT_EQ(writer_run_id(reader.handle(), reader.owner()), process_run_id());
  EXPECT_EQ(counter(kOtherRunWriters), 1u);
  EXPECT_EQ(counter(kTakeOvers), 0u);
}

// The end of a run: the owner is deleted (its process exits cleanly) while a writer of another run is
// still alive with a sample sent: nothing of it is ever handed out, before or after.
TEST_F(CheckedReaderTest, AWriterOfAnotherRunNeverTakesOverWhenTheOwnerLeavesCleanly) {
  Participant reading = make_participant();
  Participant stray_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  Writer<msg::Odometry> stray = writer_of_run(stray_participant, kOtherRun);
  {
    Participant owner_participant = make_participant();
    Writer<msg::Odometry> owner(owner_participant, topics.odometry());
    ASSERT_TRUE(owner.wait_for_readers(1, kDeadline));
    ASSERT_TRUE(stray.wait_for_readers(1, kDeadline));
    owner.write(odometry(0, 1.0));
    ASSERT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{0}));
    stray.write(odometry(1, 1.0));  // valid, but another run's
    EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 1).empty());
    owner.write(odometry(1, 2.0));
    EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{1}));
  }  // the owner is deleted: the end of its stream
  stray.write(odometry(2, 1.0));
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 2).empty());
  EXPECT_FALSE(reader.has_unread());
  EXPECT_EQ(counter(kSecondWriterSamples), 2u);
  EXPECT_EQ(counter(kSecondWriters), 1u);
  EXPECT_EQ(counter(kOtherRunWriters), 1u);
  EXPECT_EQ(counter(kTakeOvers), 0u);
}

// The owner, a writer process, crashes (kill -9: it stays matched until its lease expires). A writer
// of another run wrote before the restarted publisher of the owner's run did: only the restarted one
// takes over, its held samples first.
TEST_F(CheckedReaderTest, OnlyAWriterOfTheOwnersRunTakesOverWhenTheOwnerCrashes) {
  const std::string owners_run = "31337:7";  // the crashed writer's supervisor, say
  const test::ScratchDir dir("checked_reader_crash");
  Participant reading = make_participant();
  Participant stray_participant = make_participant();
  Participant restarted_participant = make_participant();
  CheckedReader<msg::Odometry> reader(reading, topics.odometry(), log, stats, finite_pose, options());
  test::ChildProcess owner(test::bin_dir() / "heslam-test-odometry-writer",
                           {std::to_string(test::test_domain_id()), topic_namespace, owners_run, "2"}, dir.path(),
                           "owner");
  ASSERT_EQ(take_seqs(reader, 2), (std::vector<std::uint64_t>{0, 1})) << owner.err();
  Writer<msg::Odometry> stray = writer_of_run(stray_participant, kOtherRun);
  Writer<msg::Odometry> restarted = writer_of_run(restarted_participant, owners_run);
  ASSERT_TRUE(stray.wait_for_readers(1, kDeadline));
  ASSERT_TRUE(restarted.wait_for_readers(1, kDeadline));
  stray.write(odometry(1'000'000, 1.0));  // the oldest sample of a second writer
  restarted.write(odometry(2, 1.0));      // a restart's first samples while the owner is alive: held
  restarted.write(odometry(3, 1.0));
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 3).empty());
  owner.signal(SIGKILL);
  ASSERT_EQ(owner.wait(kDeadline), 128 + SIGKILL);
  stray.write(odometry(1'000'001, 1.0));
  std::vector<std::uint64_t> seqs;
  const auto deadline = std::chrono::steady_clock::now() + kCrashDeadline;
  while (seqs.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    for (auto& received : reader.take()) {
      if (received.info.valid_data) seqs.push_back(received.sample->seq);
    }
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(seqs, (std::vector<std::uint64_t>{2, 3}));
  restarted.write(odometry(4, 1.0));
  EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{4}));
  stray.write(odometry(1'000'002, 1.0));
  EXPECT_TRUE(take_until_counted(reader, kSecondWriterSamples, 5).empty());
  EXPECT_EQ(counter(kTakeOvers), 1u);
  EXPECT_EQ(counter(kOtherRunWriters), 1u);
  EXPECT_EQ(counter(kSecondWriters), 2u);        // the stray, and the restart while the owner lived
  EXPECT_EQ(counter(kSecondWriterSamples), 5u);  // 3 of the stray, 2 held of the restart
  EXPECT_EQ(counter(kWriterConflicts), 0u);      // a restart is no conflict: its predecessor is dead
}

// RoleBinding (runtime/role_binding.hpp), the acknowledgements' guard: the writer handle of the next
// FrameDone that `reader` takes (0 when none arrived in time).
dds_instance_handle_t next_writer(Reader<msg::FrameDone>& reader) {
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (std::chrono::steady_clock::now() < deadline) {
    for (auto& received : reader.take()) {
      if (received.info.valid_data) return received.info.publication_handle;
    }
    std::this_thread::sleep_for(5ms);
  }
  return 0;
}

msg::FrameDone frame_done(std::uint64_t seq) {
  msg::FrameDone done{};
  done.seq = seq;
  return done;
}

// A forger acknowledged frame 1 first; the real consumer acknowledges it too while the forger lives
// and frame 1 is still awaited: a conflict at once, the second refused.
TEST_F(CheckedReaderTest, RoleBindingTwoLiveAcknowledgersOfOneSubjectAreAConflict) {
  Participant reading = make_participant();
  Participant first_participant = make_participant();
  Participant second_participant = make_participant();
  Reader<msg::FrameDone> reader(reading, topics.frame_done());
  Writer<msg::FrameDone> first(first_participant, topics.frame_done());
  Writer<msg::FrameDone> second(second_participant, topics.frame_done());
  ASSERT_TRUE(first.wait_for_readers(1, kDeadline));
  ASSERT_TRUE(second.wait_for_readers(1, kDeadline));
  RoleBinding roles(log, stats, topics.frame_done().name);
  first.write(frame_done(1));
  const dds_instance_handle_t first_handle = next_writer(reader);
  ASSERT_NE(first_handle, 0u);
  EXPECT_EQ(roles.claim(reader.handle(), "consumer", first_handle, 1), RoleBinding::Claim::kAccepted);
  second.write(frame_done(1));
  const dds_instance_handle_t second_handle = next_writer(reader);
  ASSERT_NE(second_handle, 0u);
  EXPECT_EQ(roles.claim(reader.handle(), "consumer", second_handle, 1), RoleBinding::Claim::kRefused);
  EXPECT_EQ(roles.conflicts(), 1u);
  EXPECT_EQ(counter(kWriterConflicts), 1u);
  EXPECT_EQ(counter(std::string(kWriterConflictsOn) + topics.frame_done().name), 1u);
  EXPECT_EQ(roles.claim(reader.handle(), "consumer", second_handle, 2), RoleBinding::Claim::kRefused);
}

// A restarted consumer acknowledges while its predecessor still counts as matched: held, then it
// takes the role over once the predecessor is gone, without a conflict; the first writing again
// while a held one lives is a conflict.
TEST_F(CheckedReaderTest, RoleBindingARestartTakesOverAndALiveFirstWriterMakesAConflict) {
  Participant reading = make_participant();
  Participant second_participant = make_participant();
  Reader<msg::FrameDone> reader(reading, topics.frame_done());
  Writer<msg::FrameDone> second(second_participant, topics.frame_done());
  RoleBinding roles(log, stats, topics.frame_done().name);
  dds_instance_handle_t second_handle = 0;
  {
    Participant first_participant = make_participant();
    Writer<msg::FrameDone> first(first_participant, topics.frame_done());
    ASSERT_TRUE(first.wait_for_readers(1, kDeadline));
    ASSERT_TRUE(second.wait_for_readers(1, kDeadline));
    first.write(frame_done(1));
    const dds_instance_handle_t first_handle = next_writer(reader);
    ASSERT_EQ(roles.claim(reader.handle(), "consumer", first_handle, 1), RoleBinding::Claim::kAccepted);
    roles.done(1);
    second.write(frame_done(2));
    second_handle = next_writer(reader);
    EXPECT_EQ(roles.claim(reader.handle(), "consumer", second_handle, 2), RoleBinding::Claim::kHeld);
  }  // the first leaves (a clean exit; a killed one is unmatched once its lease expires)
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  RoleBinding::Claim claim = RoleBinding::Claim::kHeld;
  while (claim == RoleBinding::Claim::kHeld && std::chrono::steady_clock::now() < deadline) {
    claim = roles.claim(reader.handle(), "consumer", second_handle, 2, /*again=*/true);
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(claim, RoleBinding::Claim::kAccepted);
  EXPECT_EQ(roles.conflicts(), 0u);
  EXPECT_EQ(counter("role_take_overs"), 1u);

  // Now the second owns the role; a third writer held while it lives, then the owner writes again.
  Participant third_participant = make_participant();
  Writer<msg::FrameDone> third(third_participant, topics.frame_done());
  ASSERT_TRUE(third.wait_for_readers(1, kDeadline));
  third.write(frame_done(3));
  const dds_instance_handle_t third_handle = next_writer(reader);
  EXPECT_EQ(roles.claim(reader.handle(), "consumer", third_handle, 3), RoleBinding::Claim::kHeld);
  EXPECT_EQ(roles.conflicts(), 0u);
  EXPECT_EQ(roles.claim(reader.handle(), "consumer", second_handle, 3), RoleBinding::Claim::kAccepted);
  EXPECT_EQ(roles.conflicts(), 1u);
  EXPECT_EQ(roles.claim(reader.handle(), "consumer", third_handle, 4), RoleBinding::Claim::kRefused);
}

}  // namespace
}  // namespace heslam::runtime
