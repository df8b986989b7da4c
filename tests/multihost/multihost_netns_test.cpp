// The pipeline over two hosts: two network namespaces joined by a veth pair (made by the test, one
// address each), the same pipeline file started on both with --host camera / --host server and the
// DDS network profile. Needs root and `ip netns` (skipped otherwise) and ../shared/data.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

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
                                  "--host", group, "--domain", std::to_string(domain), "--log-dir",
                                  (dir_.path() / ("logs_" + label + "_" + group)).string(),
                                  "--arg", "dds_profile=network", "--arg", "dds_interface=" + hosts_->interface(host),
                                  "--arg", "dds_peers=" + hosts_->peers(), "--arg", "dataset=" + dataset_.string(),
                                  "--arg", "output=" + (dir_.path() / (label + ".txt")).string()};
    args.insert(args.end(), more_args.begin(), more_args.end());
    return hosts_->spawn(host, test::bin_dir() / "heslam-supervisor", args, dir_.path(), "supervisor_" + label + "_" + group);
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
  std::cout << "[ figures ] MH01 lockstep over two namespaces: ATE " << test::ate_rmse_m(dataset_, dir_.path() / "two.txt") * 1000
            << " mm (single host " << test::ate_rmse_m(dataset_, dir_.path() / "single.txt") * 1000 << " mm), "
            << std::count(split.begin(), split.end(), '\n') << " poses\n";
}

// Real time, and the link between the hosts cut for 2 s mid-run: the run goes on and ends normally;
// every keyframe the frontend made reaches the mapper on the other host (keyframes are reliable and
// transient-local, and the 10 s lease of the network profile outlasts the cut, so the writer
// retransmits). Images never cross the link (replay and frontend share the camera host).
TEST_F(MultiHost, RealTimeRunSurvivesATwoSecondLinkCut) {
  const int domain = test::exclusive_domain_id();
  // Half the recording's rate (a 10 Hz camera, 16 s): room for the cut inside the run on a loaded machine.
  auto server = start_half(kServer, "euroc_realtime", "cut", domain, {"--arg", "rate=0.5"});
  auto camera = start_half(kCamera, "euroc_realtime", "cut", domain, {"--arg", "rate=0.5"});
  // Wait for frames to flow (the recorder's file grows), then pull the cable for 2 s.
  const auto trajectory = dir_.path() / "cut.txt";
  const auto deadline = std::chrono::steady_clock::now() + 120s;
  while (std::chrono::steady_clock::now() < deadline && !camera->wait(100ms)) {
    if (std::filesystem::exists(trajectory) && std::filesystem::file_size(trajectory) > 2000) break;
  }
  ASSERT_TRUE(hosts_->set_link(false));
  std::this_thread::sleep_for(2s);
  ASSERT_TRUE(hosts_->set_link(true));
  // The replay runs at half the recording's rate (16 s), so the cut fell in the middle of the run.
  ASSERT_FALSE(camera->wait(0ms)) << "the run ended before the link came back: " << camera->err();

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
  const std::string poses = read_file(trajectory);
  std::cout << "[ figures ] MH01 real time over two namespaces, link down 2 s: " << made << " keyframes made, "
            << mapped << " mapped on the other host, " << std::count(poses.begin(), poses.end(), '\n')
            << " poses, ATE " << test::ate_rmse_m(dataset_, trajectory) * 1000 << " mm\n";
}

}  // namespace
}  // namespace heslam
