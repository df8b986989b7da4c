// request_shutdown() and SIGTERM wake a blocked WaitSet (own executable: shutdown is process-wide).
#include <signal.h>

#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "runtime/participant.hpp"
#include "runtime/shutdown.hpp"
#include "runtime/waitset.hpp"
#include "test_domain.hpp"

namespace heslam::runtime {
namespace {

TEST(Shutdown, SigtermWakesABlockedWaitSet) {
  install_shutdown_handlers();
  Participant participant(ParticipantOptions{test::test_domain_id(), ""});
  WaitSet waitset(participant);
  ASSERT_FALSE(shutdown_requested());
  std::thread killer([] { kill(getpid(), SIGTERM); });
  // A bound for a broken build only; the signal arrives within milliseconds.
  EXPECT_EQ(waitset.wait(std::chrono::seconds(30)), Wake::kShutdown);
  killer.join();
  EXPECT_TRUE(shutdown_requested());
  EXPECT_EQ(shutdown_signal(), SIGTERM);
  WaitSet later(participant);  // created after the request: returns at once
  EXPECT_EQ(later.wait(std::chrono::seconds(30)), Wake::kShutdown);
}

}  // namespace
}  // namespace heslam::runtime
