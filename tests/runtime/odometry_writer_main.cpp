// heslam-test-odometry-writer: one odometry writer in its own process, for the CheckedReader test of
// an owner that crashes (kill -9: its writer stays matched until the 2 s lease expires, unlike a
// writer deleted at a clean exit). Writes seq 0..COUNT-1 once a reader matched, prints "written",
// then stays alive until killed.
//
//   heslam-test-odometry-writer DOMAIN TOPIC_NAMESPACE RUN_ID COUNT
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "runtime/messages.hpp"
#include "runtime/participant.hpp"
#include "runtime/topics.hpp"
#include "runtime/writer.hpp"

namespace {

// Discovery on loopback takes milliseconds; this bounds a broken run.
constexpr std::chrono::seconds kReaderWait{10};
// Alive "forever" for a test: the test kills it long before; bounds an orphan if the test dies.
constexpr std::chrono::seconds kLifetime{60};

}  // namespace

int main(int argc, char** argv) {
  using namespace heslam::runtime;
  if (argc != 5) {
    std::fprintf(stderr, "usage: heslam-test-odometry-writer DOMAIN TOPIC_NAMESPACE RUN_ID COUNT\n");
    return 2;
  }
  const Participant participant(ParticipantOptions{std::stoi(argv[1]), ""});
  const Topics topics(argv[2]);
  Writer<heslam::msg::Odometry> writer(participant, topics.odometry(), Qos(QosRole::kOdometry).run_identity(argv[3]));
  if (!writer.wait_for_readers(1, kReaderWait)) {
    std::fprintf(stderr, "no reader matched within %lld s\n", static_cast<long long>(kReaderWait.count()));
    return 1;
  }
  const int count = std::stoi(argv[4]);
  for (int seq = 0; seq < count; ++seq) {
    heslam::msg::Odometry sample{};
    sample.seq = static_cast<std::uint64_t>(seq);
    sample.T_wc.orientation_xyzw[3] = 1.0;
    writer.write(sample);
  }
  std::printf("written\n");
  std::fflush(stdout);
  std::this_thread::sleep_for(kLifetime);
  return 0;
}
