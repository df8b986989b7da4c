// CheckedReader (issue 16 section 3): validation with a counted, rate-limited warning, the first
// writer owning the stream, a second writer's samples held and ignored while the first is alive, and
// its take-over (held samples first, in order) once the first writer is gone — the restarted-publisher
// case. Writers sit in their own participants, as other processes would.
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "runtime/checked_reader.hpp"
#include "runtime/participant.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"
#include "test_domain.hpp"

namespace heslam::runtime {
namespace {

using namespace std::chrono_literals;

// Discovery + delivery on loopback take milliseconds; this only bounds a broken run.
constexpr auto kDeadline = 5s;

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

  // Nothing more arrives within a short while (what a second writer sent is held back).
  std::vector<std::uint64_t> take_for(CheckedReader<msg::Odometry>& reader, std::chrono::milliseconds period) {
    std::vector<std::uint64_t> seqs;
    const auto until = std::chrono::steady_clock::now() + period;
    while (std::chrono::steady_clock::now() < until) {
      for (auto& received : reader.take()) {
        if (received.info.valid_data) seqs.push_back(received.sample->seq);
      }
      std::this_thread::sleep_for(5ms);
    }
    return seqs;
  }

  std::uint64_t counter(const std::string& name) const {
    const auto counters = stats.counters();
    return counters.count(name) != 0 ? counters.at(name) : 0;
  }

  Topics topics{"checkedreadertest_" + std::to_string(getpid())};
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
  first.write(odometry(1, 1.0));
  // Only the first writer's sample comes out.
  EXPECT_EQ(take_for(reader, 300ms), (std::vector<std::uint64_t>{1}));
  EXPECT_EQ(counter(kSecondWriterSamples), 2u);
  EXPECT_EQ(counter("second_writers"), 1u);
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
    EXPECT_TRUE(take_for(reader, 200ms).empty());
  }  // the first writer is deleted
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
    EXPECT_TRUE(take_for(reader, 200ms).empty());
  }
  // A lockstep publisher sends one frame and waits: nothing new arrives to trigger the take-over.
  const auto deadline = std::chrono::steady_clock::now() + kDeadline;
  while (!reader.has_unread() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(5ms);
  EXPECT_EQ(take_seqs(reader, 1), (std::vector<std::uint64_t>{5}));
}

}  // namespace
}  // namespace heslam::runtime
