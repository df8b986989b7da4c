// The pipeline over two hosts: two network namespaces joined by a veth pair (made by the test, one
// address each), the same pipeline file started on both with --host camera / --host server and the
// DDS network profile. Needs root and `ip netns` (skipped otherwise) and ../shared/data.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/types.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>
#include <vector>

#include "netns_pair.hpp"
#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

using namespace std::chrono_literals;

constexpr int kCamera = 0;  // replay, frontend, recorder (and the viewer, disabled)
constexpr int kServer = 1;  // local mapper, loop closer

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The first integer captured by `pattern` in the log file, -1 if absent.
long long number_in(const std::filesystem::path& log, const std::string& pattern) {
  std::smatch match;
  const std::string text = read_file(log);
  return std::regex_search(text, match, std::regex(pattern)) ? std::stoll(match[1].str()) : -1;
}

// Bound of each wait on the pipeline (a hung run fails instead of blocking ctest; not a speed).
constexpr auto kPipelineBound = std::chrono::seconds(300);
// How long the link between the hosts is down, the replay running meanwhile.
constexpr auto kLinkDown = std::chrono::seconds(2);

// Poses in a trajectory file the recorder writes (its '#' header lines left out).
long long count_poses(const std::filesystem::path& path) {
  std::istringstream text(read_file(path));
  long long poses = 0;
  for (std::string line; std::getline(text, line);) poses += !line.empty() && line[0] != '#';
  return poses;
}

// The pid of parent's child whose command name is `name` (/proc/PID/stat), 0 if none.
pid_t child_named(pid_t parent, const std::string& name) {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/proc", error)) {
    const std::string stat = read_file(entry.path() / "stat");
    const auto open = stat.find('('), close = stat.rfind(')');
    if (open == std::string::npos || close == std::string::npos || stat.substr(open + 1, close - open - 1) != name)
      continue;
    std::istringstream rest(stat.substr(close + 1));
    std::string state;
    pid_t ppid = 0;
    if (rest >> state >> ppid && ppid == parent) return std::stoi(entry.path().filename().string());
  }
  return 0;
}

// True once pid catches SIGUSR1 and SIGUSR2 (the SigCgt mask of /proc/PID/status).
bool handles_pause_signals(pid_t pid) {
  const std::string status = read_file(std::filesystem::path("/proc") / std::to_string(pid) / "status");
  const auto at = status.find("SigCgt:");
  if (at == std::string::npos) return false;
  const unsigned long long caught = std::stoull(status.substr(at + 7, status.find('\n', at) - at - 7), nullptr, 16);
  const auto bit = [](int signal) { return 1ULL << (signal - 1); };
  return (caught & bit(SIGUSR1)) && (caught & bit(SIGUSR2));
}

class MultiHost : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto why = test::NetnsPair::unavailable()) GTEST_SKIP() << "multi-host test skipped: " << *why;
    dataset_ = test::shared_dataset("euroc_mh01_handheld");
    if (dataset_.empty()) GTEST_SKIP() << "../shared/data/euroc_mh01_handheld is absent";
    hosts_ = std::make_unique<test::NetnsPair>();
    ASSERT_TRUE(hosts_->ok()) << "could not make the two namespaces and their veth link";
  }

  // The pipeline's half for `host` inside its namespace, on the network profile.
  std::unique_ptr<test::ChildProcess> start_half(int host, const std::string& pipeline, const std::string& label,
                                                 int domain, const std::vector<std::string>& more_args = {}) {
    const std::string group = host == kCamera ? "camera" : "server";
    std::vector<std::string> args{(test::source_dir() / "config/pipelines" / (pipeline + ".yaml")).string(),
                                  "--host",
                                  group,
                                  "--domain",
                                  std::to_string(domain),
                                  "--log-dir",
                                  (dir_.path() / ("logs_" + label + "_" + group)).string(),
                                  "--arg",
                                  "dds_profile=network",
                                  "--arg",
                                  "dds_interface=" + hosts_->interface(host),
                                  "--arg",
                                  "dds_peers=" + hosts_->peers(),
                                  "--arg",
                                  "dataset=" + dataset_.string(),
                                  "--arg",
                                  "output=" + (dir_.path() / (label + ".txt")).string()};
    args.insert(args.end(), more_args.begin(), more_args.end());
    return hosts_->spawn(host, test::bin_dir() / "heslam-supervisor", args, dir_.path(),
                         "supervisor_" + label + "_" + group);
  }

  std::filesystem::path dataset_;
  std::unique_ptr<test::NetnsPair> hosts_;
  test::ScratchDir dir_{"multihost"};
};

// Lockstep is deterministic, so splitting the processes over two hosts changes nothing: the
// trajectory file is byte for byte the one of the single-host run.
TEST_F(MultiHost, LockstepOverTwoHostsIsBitIdenticalToOneHost) {
  const int domain = test::exclusive_domain_id();
  auto single = test::start_pipeline("euroc", dataset_, dir_.path(), "single", domain);
  ASSERT_EQ(test::finish(*single), 0) << single->err();

  // Server first, as a user would start the map server; it waits for the camera host's recorder.
  auto server = start_half(kServer, "euroc", "two", domain);
  auto camera = start_half(kCamera, "euroc", "two", domain);
  const test::StopRunsOnExit stop_runs({camera.get(), server.get()});
  const int camera_code = test::finish(*camera);
  const int server_code = test::finish(*server, 60s);
  EXPECT_EQ(camera_code, 0) << camera->err();
  EXPECT_EQ(server_code, 0) << server->err();
  EXPECT_NE(server->err().find("is ending the run; stopping here too"), std::string::npos) << server->err();
  EXPECT_NE(camera->err().find("local_mapper (another host) is ready"), std::string::npos) << camera->err();

  const std::string reference = read_file(dir_.path() / "single.txt");
  const std::string split = read_file(dir_.path() / "two.txt");
  ASSERT_FALSE(reference.empty());
  EXPECT_EQ(split, reference) << "the two-host trajectory differs from the single-host one";
  EXPECT_EQ(read_file(dir_.path() / "two.keyframes.txt"), read_file(dir_.path() / "single.keyframes.txt"));
  std::cout << "[ figures ] MH01 lockstep over two namespaces: ATE "
            << test::ate_rmse_m(dataset_, dir_.path() / "two.txt") * 1000 << " mm (single host "
            << test::ate_rmse_m(dataset_, dir_.path() / "single.txt") * 1000 << " mm), "
            << count_poses(dir_.path() / "two.txt") << " poses\n";
}

// Real time, and the link between the hosts cut for 2 s mid-run: the run goes on and ends normally;
// every keyframe the frontend made reaches the mapper on the other host (keyframes are reliable and
// transient-local, and the 10 s lease of the network profile outlasts the cut, so the writer
// retransmits). Images never cross the link (replay and frontend share the camera host).
// No speed is assumed: the test holds the replay (SIGUSR1 pauses it, SIGUSR2 resumes it) while it
// waits for the pipeline, so the replay runs only until the first pose and while the link is down
// (2 s of its 16 s at half rate), and the run cannot end before the link is back however slow the
// machine. How long the data took to cross again is printed as a figure, not asserted.
TEST_F(MultiHost, RealTimeRunSurvivesATwoSecondLinkCut) {
  const int domain = test::exclusive_domain_id();
  auto server = start_half(kServer, "euroc_realtime", "cut", domain, {"--arg", "rate=0.5"});
  auto camera = start_half(kCamera, "euroc_realtime", "cut", domain, {"--arg", "rate=0.5"});
  const test::StopRunsOnExit stop_runs({camera.get(), server.get()});
  const auto deadline = std::chrono::steady_clock::now() + kPipelineBound;
  // Polls `done` every 20 ms while the camera host's run goes on (at most until the deadline).
  const auto wait_until = [&](const auto& done) {
    while (!done() && std::chrono::steady_clock::now() < deadline && !camera->wait(20ms)) {
    }
    return done();
  };

  // The replay, once it handles the pause/resume signals (the default action of SIGUSR1 kills).
  pid_t replay = 0;
  ASSERT_TRUE(wait_until([&] { return (replay = child_named(camera->pid(), "heslam-replay")) != 0; }))
      << "no heslam-replay under the camera host's supervisor: " << camera->err();
  ASSERT_TRUE(wait_until([&] { return handles_pause_signals(replay); }))
      << "heslam-replay never installed its SIGUSR1/SIGUSR2 handlers: " << camera->err();

  // Frames flow (the recorder wrote a pose): hold the replay, and wait until the first keyframe has
  // crossed the link (the mapper on the server host wrote its map file) before cutting it.
  const auto trajectory = dir_.path() / "cut.txt";
  const auto server_map = dir_.path() / "cut.map";
  const auto replay_started = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until([&] { return count_poses(trajectory) > 0; })) << "no pose recorded: " << camera->err();
  ASSERT_EQ(kill(replay, SIGUSR1), 0) << "the replay ended before the first pose was recorded: " << camera->err();
  const auto first_pose = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until([&] { return std::filesystem::exists(server_map); }))
      << "no keyframe reached the mapper before the cut: " << server->err();

  // Pull the cable, let the replay run 2 s (the frontend goes on making keyframes the mapper cannot
  // get yet), hold the replay again, plug the cable back, let the replay finish.
  ASSERT_TRUE(hosts_->set_link(false));
  ASSERT_EQ(kill(replay, SIGUSR2), 0);
  std::this_thread::sleep_for(kLinkDown);
  ASSERT_EQ(kill(replay, SIGUSR1), 0);
  ASSERT_FALSE(camera->wait(0ms)) << "the replay reached its end during the cut (it had run from its start to the "
                                     "first pose and 2 s more): "
                                  << camera->err();
  const auto poses_in_cut = count_poses(trajectory);
  ASSERT_TRUE(hosts_->set_link(true));
  const auto link_up = std::chrono::steady_clock::now();
  const auto map_before = std::filesystem::last_write_time(server_map);
  ASSERT_EQ(kill(replay, SIGUSR2), 0);

  // Data crosses again: the first map write after the link came back (a figure, not a bound).
  std::optional<std::chrono::steady_clock::duration> resumed_after;
  while (!camera->wait(20ms) && std::chrono::steady_clock::now() < deadline) {
    std::error_code error;
    if (!resumed_after && std::filesystem::last_write_time(server_map, error) != map_before && !error) {
      resumed_after = std::chrono::steady_clock::now() - link_up;
    }
  }
  const int camera_code = test::finish(*camera);
  const int server_code = test::finish(*server, 60s);
  EXPECT_EQ(camera_code, 0) << camera->err();
  EXPECT_EQ(server_code, 0) << server->err();
  const auto camera_logs = dir_.path() / "logs_cut_camera";
  const auto server_logs = dir_.path() / "logs_cut_server";
  const long long made = number_in(camera_logs / "frontend.log", R"(, (\d+) keyframes)");
  const long long mapped = number_in(server_logs / "local_mapper.log", R"(mapped (\d+) keyframes)");
  ASSERT_GT(made, 0) << read_file(camera_logs / "frontend.log");
  EXPECT_EQ(mapped, made) << "keyframes lost across the link cut";
  const auto ms = [](auto duration) { return std::chrono::duration_cast<std::chrono::milliseconds>(duration).count(); };
  std::cout << "[ figures ] MH01 real time over two namespaces, link down " << ms(kLinkDown) << " ms: " << made
            << " keyframes made, " << mapped << " mapped on the other host, " << count_poses(trajectory) << " poses ("
            << poses_in_cut << " by the end of the cut), ATE " << test::ate_rmse_m(dataset_, trajectory) * 1000
            << " mm; first pose " << ms(first_pose - replay_started)
            << " ms after the replay started; first map write after the link came back: "
            << (resumed_after ? std::to_string(ms(*resumed_after)) + " ms" : std::string("none before the run ended"))
            << "\n";
}

}  // namespace
}  // namespace heslam
