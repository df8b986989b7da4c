// Several agents on several hosts (docs/agents.md, docs/deployment.md): config/pipelines/euroc_two_agents.yaml
// over two network namespaces joined by a veth pair (made by the test), agent b (its replay, frontend and
// recorder) on the second host, the local mapper, the loop closer and agent a on the first, each side started
// with --host and the DDS network profile. The MH01 clip's two overlapping halves as the single-host test
// uses them (frames 0-99 and 60-159, made here). Lockstep with turns is deterministic, so splitting the
// processes over two hosts changes nothing: both trajectories and keyframe files are byte for byte those of
// the same pipeline on one host (run beside it). Needs root and `ip netns` (skipped otherwise) and
// ../shared/data.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "euroc_parts.hpp"
#include "netns_pair.hpp"
#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr int kHostA = 0;  // agent a, local mapper, loop closer
constexpr int kHostB = 1;  // agent b
constexpr int kFramesPerAgent = 100;

std::string file_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(MultiHostAgents, AgentBOnAnotherHostIsBitIdenticalToOneHost) {
  if (const auto why = test::NetnsPair::unavailable()) GTEST_SKIP() << "multi-host test skipped: " << *why;
  const fs::path clip = test::shared_dataset("euroc_mh01_handheld");
  if (clip.empty()) GTEST_SKIP() << "../shared/data/euroc_mh01_handheld is absent";
  const test::NetnsPair hosts;
  ASSERT_TRUE(hosts.ok()) << "could not make the two namespaces and their veth link";
  const test::ScratchDir dir("multihost_agents");
  const fs::path half_a = dir.path() / "half_a";
  const fs::path half_b = dir.path() / "half_b";
  test::make_euroc_part(clip, half_a, 0, kFramesPerAgent);
  test::make_euroc_part(clip, half_b, 60, kFramesPerAgent);
  const fs::path pipeline = test::source_dir() / "config/pipelines/euroc_two_agents.yaml";
  const std::vector<std::string> datasets{"--arg", "dataset_a=" + half_a.string(), "--arg",
                                          "dataset_b=" + half_b.string()};

  // One host (the test's own namespace, loopback) ...
  std::vector<std::string> one_host{pipeline.string(),
                                    "--domain",
                                    std::to_string(test::exclusive_domain_id()),
                                    "--log-dir",
                                    (dir.path() / "logs_single").string(),
                                    "--arg",
                                    "output=" + (dir.path() / "single.txt").string()};
  one_host.insert(one_host.end(), datasets.begin(), datasets.end());
  test::ChildProcess single(test::bin_dir() / "heslam-supervisor", one_host, dir.path(), "supervisor_single");

  // ... and beside it the same run over two hosts: both sides of the split start at once (each waits for
  // the other's components through the status topic).
  const int domain = test::exclusive_domain_id();
  const auto start_host = [&](int host) {
    const std::string group = host == kHostA ? "a" : "b";
    std::vector<std::string> args{pipeline.string(),
                                  "--host",
                                  group,
                                  "--domain",
                                  std::to_string(domain),
                                  "--log-dir",
                                  (dir.path() / ("logs_split_" + group)).string(),
                                  "--arg",
                                  "dds_profile=network",
                                  "--arg",
                                  "dds_interface=" + hosts.interface(host),
                                  "--arg",
                                  "dds_peers=" + hosts.peers(),
                                  "--arg",
                                  "output=" + (dir.path() / "split.txt").string()};
    args.insert(args.end(), datasets.begin(), datasets.end());
    return hosts.spawn(host, test::bin_dir() / "heslam-supervisor", args, dir.path(), "supervisor_split_" + group);
  };
  auto host_a = start_host(kHostA);
  auto host_b = start_host(kHostB);
  const test::StopRunsOnExit stop_runs({host_a.get(), host_b.get()});
  const int single_code = test::finish(single);
  const int a_code = test::finish(*host_a);
  const int b_code = test::finish(*host_b, 60s);
  ASSERT_EQ(single_code, 0) << single.err();
  EXPECT_EQ(a_code, 0) << host_a->err();
  EXPECT_EQ(b_code, 0) << host_b->err();

  for (const std::string agent : {"a", "b"}) {
    for (const std::string file : {".txt", ".keyframes.txt"}) {
      const std::string reference = file_text(dir.path() / ("single." + agent + file));
      ASSERT_FALSE(reference.empty()) << "single." << agent << file;
      EXPECT_EQ(file_text(dir.path() / ("split." + agent + file)), reference)
          << "agent " << agent << "'s " << file << " over two hosts differs from the single-host run's";
    }
  }
  EXPECT_EQ(eval::read_trajectory(dir.path() / "split.b.txt").size(), static_cast<std::size_t>(kFramesPerAgent));
  EXPECT_NE((host_a->out() + host_a->err()).find("maps merged"), std::string::npos) << host_a->err();
  std::cout << "[ figures ] MH01 halves as two agents, agent b on another host: ATE a "
            << test::ate_rmse_m(half_a, dir.path() / "split.a.txt") * 1000 << " mm, b "
            << test::ate_rmse_m(half_b, dir.path() / "split.b.txt") * 1000 << " mm (each aligned alone)\n";
}

}  // namespace
}  // namespace heslam
