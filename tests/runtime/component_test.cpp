// Component base in-process: subscribe() handlers run from spin(), stats reach ComponentStatus
// (state, counters, stage percentiles, RSS), request_shutdown() ends run(). Own executable: shutdown
// is process-wide.
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "runtime/component.hpp"
#include "runtime/sequence.hpp"
#include "test_domain.hpp"

namespace heslam::runtime {
namespace {

using namespace std::chrono_literals;

constexpr uint64_t kFrames = 5;

class Counter : public Component {
 public:
  explicit Counter(const CommonArgs& args) : Component("counter", args) {}
  std::vector<uint64_t> seen;

 private:
  void configure(const Config& config) override {
    stage_ = config.get_string("stage", "handle");
    subscribe(topics().frame_done(), [this](Received<msg::FrameDone>& received) {
      {
        auto timer = stats().time(stage_);
        seen.push_back(received.sample->seq);
        stats().count("frames");
      }
      if (seen.size() == kFrames) {
        status().publish_now();
        done_at_ = std::chrono::steady_clock::now();
      }
    });
  }
  void run() override {
    // Keep spinning a little after the last frame so the test can read the status.
    while (spin_once(50ms)) {
      if (done_at_ && std::chrono::steady_clock::now() - *done_at_ > 3s) request_shutdown();
    }
  }
  std::string stage_;
  std::optional<std::chrono::steady_clock::time_point> done_at_;
};

TEST(Component, SubscriptionsStatusAndShutdown) {
  CommonArgs args;
  args.domain_id = test::test_domain_id();
  args.ns = "componenttest_" + std::to_string(getpid());
  args.name = "counter-1";
  Counter counter(args);

  Participant participant(ParticipantOptions{args.domain_id, ""});
  Topics topics(args.ns);
  Writer<msg::FrameDone> writer(participant, topics.frame_done());
  Reader<msg::ComponentStatus> status_reader(participant, topics.status());

  int exit_code = -1;
  std::thread runner([&] { exit_code = counter.execute(); });
  ASSERT_TRUE(writer.wait_for_readers(1, 10s));
  std::string component = "test";
  for (uint64_t seq = 0; seq < kFrames; ++seq) {
    msg::FrameDone done{};
    done.seq = seq;
    done.component = borrow(component);
    writer.write(done);
  }
  // The status after the last frame: RUNNING, 5 frames, one stage with 5 timings, some RSS.
  bool found = false;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!found && std::chrono::steady_clock::now() < deadline) {
    for (auto& received : status_reader.take()) {
      const msg::ComponentStatus& status = *received.sample;
      if (!received.info.valid_data || to_string(status.name) != "counter-1") continue;
      const auto counters = view(status.counters);
      if (counters.empty() || counters[0].value != kFrames) continue;
      found = true;
      EXPECT_EQ(status.state, heslam_msg_STATE_RUNNING);
      EXPECT_EQ(status.pid, getpid());
      EXPECT_EQ(to_string(counters[0].name), "frames");
      ASSERT_EQ(view(status.stages).size(), 1u);
      EXPECT_EQ(to_string(view(status.stages)[0].name), "handle");
      EXPECT_EQ(view(status.stages)[0].count, kFrames);
      EXPECT_GT(status.rss_bytes, 0u);
    }
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_TRUE(found);
  runner.join();  // ends by request_shutdown() in run()
  EXPECT_EQ(exit_code, 0);
  EXPECT_EQ(counter.seen, (std::vector<uint64_t>{0, 1, 2, 3, 4}));
}

}  // namespace
}  // namespace heslam::runtime
