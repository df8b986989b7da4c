// The full synthetic pipeline (replay, frontend, local mapper, bag of words loop closer,
// recorder, supervisor) with the stereo images over iceoryx shared memory (--image-transport shm, on
// a second domain) gives the UDP run's trajectory (lockstep: bit-identical input and processing), and
// the replay's frame writer really uses shared memory (Cyclone falls back to UDP silently otherwise).
// Skipped with a message when iox-roudi is not installed (apt-get install iceoryx).
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "pipeline_runs.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 40;

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && ::access((fs::path(dir) / program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

// A second DDS domain for the images, locked like test::exclusive_domain_id() (same lock folder), so
// no concurrent test uses it: the images of this run must not reach another test's frontend.
int second_exclusive_domain_id(int first) {
  static const int domain_id = [first] {
    const fs::path lock_dir = fs::temp_directory_path() / "heslam-test-domains";
    fs::create_directories(lock_dir);
    for (int i = 1; i <= 230; ++i) {
      const int id = 1 + (first + i - 1) % 230;
      if (id == first) continue;
      const int fd = ::open((lock_dir / (std::to_string(id) + ".lock")).c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
      if (fd < 0) continue;
      if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return id;  // fd stays open: the lock lives with us
      ::close(fd);
    }
    throw std::runtime_error("no second free DDS test domain in 1..230");
  }();
  return domain_id;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(ShmPipeline, SynthRoomOverSharedMemoryGivesTheUdpTrajectory) {
  if (!on_path("iox-roudi")) {
    GTEST_SKIP() << "iox-roudi not installed (apt-get install iceoryx): the shared-memory image transport cannot run";
  }
  fs::path dataset;
  ASSERT_EQ(test::cached_synth("room", kFrames, dataset), "");
  const int domain = test::exclusive_domain_id();
  const int image_domain = second_exclusive_domain_id(domain);
  const test::ScratchDir dir("shm_pipeline");

  auto udp = test::start_pipeline("synth", dataset, dir.path(), "udp", domain);
  ASSERT_EQ(test::finish(*udp), 0) << udp->err();

  std::vector<std::string> args{(test::source_dir() / "config/pipelines/synth.yaml").string(),
                                "--domain",
                                std::to_string(domain),
                                "--image-transport",
                                "shm",
                                "--image-domain",
                                std::to_string(image_domain),
                                "--log-dir",
                                (dir.path() / "logs_shm").string(),
                                "--arg",
                                "dataset=" + dataset.string(),
                                "--arg",
                                "output=" + (dir.path() / "shm.txt").string()};
  test::ChildProcess shm(test::bin_dir() / "heslam-supervisor", args, dir.path(), "supervisor_shm");
  ASSERT_EQ(test::finish(shm), 0) << shm.err();

  const std::string summary = test::last_line(shm.err());
  std::cout << "shm run: " << summary << "\n";
  EXPECT_NE(summary.find("pipeline finished: tracked " + std::to_string(kFrames) + "/" + std::to_string(kFrames) +
                         " frames, 0 lost"),
            std::string::npos)
      << summary;
  const std::string replay_log = read_text(dir.path() / "logs_shm" / "replay.log");
  EXPECT_NE(replay_log.find("(shared memory, domain " + std::to_string(image_domain) + ")"), std::string::npos)
      << "the replay's frame writer did not use shared memory: " << replay_log;

  const eval::Trajectory udp_poses = eval::read_trajectory(dir.path() / "udp.txt");
  const eval::Trajectory shm_poses = eval::read_trajectory(dir.path() / "shm.txt");
  ASSERT_EQ(udp_poses.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(shm_poses.size(), udp_poses.size());
  double max_difference_m = 0.0;
  for (std::size_t i = 0; i < udp_poses.size(); ++i) {
    EXPECT_DOUBLE_EQ(shm_poses.stamps_s[i], udp_poses.stamps_s[i]);
    const double difference_m = (shm_poses.poses_wc[i].translation() - udp_poses.poses_wc[i].translation()).norm();
    max_difference_m = std::max(max_difference_m, difference_m);
  }
  std::cout << "[ figures ] shm vs udp images: " << shm_poses.size() << " poses, largest position difference "
            << max_difference_m << " m; ATE udp " << test::ate_rmse_m(dataset, dir.path() / "udp.txt") << " m, shm "
            << test::ate_rmse_m(dataset, dir.path() / "shm.txt") << " m\n";
  // Lockstep runs are repeatable to the last digit written; 1 um leaves room for text rounding only.
  EXPECT_LT(max_difference_m, 1e-6);
}

// Without RouDi on PATH the supervisor refuses with one line naming the package (PATH emptied).
TEST(ShmPipeline, MissingRoudiIsOneClearLine) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("shm_pipeline_no_roudi");
  std::vector<std::string> args{"PATH=/nonexistent",
                                (test::bin_dir() / "heslam-supervisor").string(),
                                (test::source_dir() / "config/pipelines/synth.yaml").string(),
                                "--domain",
                                std::to_string(domain),
                                "--image-transport",
                                "shm",
                                "--image-domain",
                                std::to_string(second_exclusive_domain_id(domain)),
                                "--log-dir",
                                (dir.path() / "logs").string(),
                                "--arg",
                                "dataset=" + dir.path().string(),
                                "--no-progress"};
  if (on_path("iox-roudi") && std::system("pidof iox-roudi >/dev/null 2>&1") == 0) {
    GTEST_SKIP() << "an iox-roudi is running on this host: the supervisor would use it";
  }
  test::ChildProcess supervisor("/usr/bin/env", args, dir.path(), "supervisor");
  EXPECT_EQ(test::finish(supervisor, std::chrono::seconds(60)), 1) << supervisor.err();
  EXPECT_NE(supervisor.err().find("image transport shm: iox-roudi not found on PATH (apt-get install iceoryx)"),
            std::string::npos)
      << supervisor.err();
}

}  // namespace
}  // namespace heslam
