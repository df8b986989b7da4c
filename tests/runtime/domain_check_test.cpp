// other_participant_on_host (runtime/supervisor/domain_check.hpp): whether the supervisor must listen
// for another run before it starts anything. With the built-in Cyclone configuration a participant of
// another process binds a discovery port of the domain; the test process's own participants do not count.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "child_process.hpp"
#include "runtime/participant.hpp"
#include "runtime/supervisor/domain_check.hpp"
#include "test_domain.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

using namespace std::chrono_literals;

// Until the answer is `wanted` (a process binds its ports as it creates its participant), bounded.
bool becomes(const supervisor::Pipeline& pipeline, int domain, bool wanted) {
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (supervisor::other_participant_on_host(pipeline, domain) == wanted) return true;
    std::this_thread::sleep_for(20ms);
  }
  return false;
}

TEST(DomainCheck, AParticipantOfAnotherProcessIsSeenOwnOnesAreNot) {
  unsetenv("CYCLONEDDS_URI");
  const int domain = test::test_domain_id();
  supervisor::Pipeline pipeline;
  pipeline.domain_id = domain;
  // Nobody on this test's domain (it holds the domain's lock): nothing to listen for.
  EXPECT_EQ(supervisor::other_participant_on_host(pipeline, domain), false);
  {
    // This process's own participant (the supervisor's, in the supervisor) is left out.
    const runtime::Participant own(runtime::ParticipantOptions{domain, ""});
    EXPECT_EQ(supervisor::other_participant_on_host(pipeline, domain), false);
    // Another process's participant on the domain: listened for.
    const std::filesystem::path logs =
        std::filesystem::temp_directory_path() / ("domain_check_" + std::to_string(getpid()));
    std::filesystem::create_directories(logs);
    test::ChildProcess talker(test::bin_dir() / "heslam-test-talker",
                              {"--domain", std::to_string(domain), "--namespace", "dc" + std::to_string(getpid())},
                              logs, "talker");
    EXPECT_TRUE(becomes(pipeline, domain, true));
    talker.signal(SIGKILL);
    talker.wait(10s);
    EXPECT_TRUE(becomes(pipeline, domain, false));
    std::filesystem::remove_all(logs);
  }
  // Another configuration may reach other hosts or use other ports: not told.
  pipeline.dds_config = "file:///nonexistent.xml";
  EXPECT_EQ(supervisor::other_participant_on_host(pipeline, domain), std::nullopt);
  pipeline.dds_config.clear();
  setenv("CYCLONEDDS_URI", "file:///nonexistent.xml", 1);
  EXPECT_EQ(supervisor::other_participant_on_host(pipeline, domain), std::nullopt);
  unsetenv("CYCLONEDDS_URI");
}

}  // namespace
}  // namespace heslam
