// Pipeline files spread over hosts (hosts: groups, --host, --only) and the DDS network profile:
// what each host runs, and one clear line for every mistake (docs/deployment.md).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <dds/dds.h>

#include "runtime/dds_network_profile.hpp"
#include "runtime/supervisor/pipeline.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

using supervisor::load_pipeline;
using supervisor::LoadResult;
using supervisor::PipelineOverrides;

class PipelineHosts : public ::testing::Test {
 protected:
  std::filesystem::path write(const std::string& text) {
    const auto file = dir_.path() / "p.yaml";
    std::ofstream(file) << text;
    return file;
  }
  LoadResult load(const std::string& text, const PipelineOverrides& overrides = {}) {
    return load_pipeline(write(text), overrides, "/bin");
  }
  static std::string problems(const LoadResult& result) {
    std::string text;
    for (const auto& problem : result.problems) text += problem + "\n";
    return text;
  }
  static bool remote(const LoadResult& result, const std::string& name) {
    for (const auto& component : result.pipeline.components) {
      if (component.name == name) return component.remote;
    }
    ADD_FAILURE() << "no component " << name;
    return false;
  }
  test::ScratchDir dir_{"pipeline_hosts"};
};

// Three harmless executables; two host groups.
constexpr const char* kTwoHosts =
    "components:\n"
    "  - {name: recorder, executable: true}\n"
    "  - {name: mapper, executable: true}\n"
    "  - {name: replay, executable: true}\n"
    "hosts:\n"
    "  camera: \"recorder, replay\"\n"
    "  server: mapper\n";

TEST_F(PipelineHosts, WithoutHostEverythingRunsHere) {
  const auto result = load(kTwoHosts);
  ASSERT_TRUE(result.problems.empty()) << problems(result);
  EXPECT_FALSE(result.pipeline.split());
  EXPECT_FALSE(remote(result, "mapper"));
}

TEST_F(PipelineHosts, HostRunsItsGroupAndMarksTheOthersRemote) {
  PipelineOverrides camera;
  camera.host = "camera";
  const auto result = load(kTwoHosts, camera);
  ASSERT_TRUE(result.problems.empty()) << problems(result);
  EXPECT_TRUE(result.pipeline.split());
  EXPECT_FALSE(remote(result, "recorder"));
  EXPECT_TRUE(remote(result, "mapper"));
  EXPECT_FALSE(remote(result, "replay"));
  // Start order is kept: the remote component stays in its place (waited for, not started).
  ASSERT_EQ(result.pipeline.components.size(), 3u);
  EXPECT_EQ(result.pipeline.components[1].name, "mapper");
}

TEST_F(PipelineHosts, InputsOfAnotherHostAreNotCheckedHere) {
  const std::string text =
      "args: {dataset: \"\"}\n"
      "components:\n"
      "  - {name: mapper, executable: true}\n"
      "  - {name: replay, executable: true, inputs: [\"$(arg dataset)\"]}\n"
      "hosts:\n  camera: replay\n  server: mapper\n";
  PipelineOverrides server;
  server.host = "server";
  EXPECT_TRUE(load(text, server).problems.empty()) << problems(load(text, server));
  PipelineOverrides camera;
  camera.host = "camera";
  EXPECT_NE(problems(load(text, camera)).find("input '$(arg dataset)' is empty"), std::string::npos);
}

TEST_F(PipelineHosts, OnlyRunsTheNamedComponents) {
  PipelineOverrides only;
  only.only = {"mapper"};
  const auto result = load(kTwoHosts, only);
  ASSERT_TRUE(result.problems.empty()) << problems(result);
  EXPECT_TRUE(remote(result, "recorder"));
  EXPECT_FALSE(remote(result, "mapper"));
}

TEST_F(PipelineHosts, UnknownHostOrComponentIsOneLine) {
  PipelineOverrides host;
  host.host = "robot";
  EXPECT_NE(
      problems(load(kTwoHosts, host)).find("--host robot: the pipeline has no such host group (hosts: camera, server)"),
      std::string::npos)
      << problems(load(kTwoHosts, host));
  PipelineOverrides only;
  only.only = {"frontend"};
  EXPECT_NE(problems(load(kTwoHosts, only)).find("--only: no component 'frontend'"), std::string::npos);
}

TEST_F(PipelineHosts, EveryComponentInExactlyOneGroup) {
  const std::string missing =
      "components:\n  - {name: a, executable: true}\n  - {name: b, executable: true}\nhosts:\n  one: a\n";
  EXPECT_NE(problems(load(missing)).find("component 'b' is in no host group"), std::string::npos);
  const std::string twice = "components:\n  - {name: a, executable: true}\nhosts:\n  one: a\n  two: a\n";
  EXPECT_NE(problems(load(twice)).find("component 'a' is already in hosts.one"), std::string::npos);
  const std::string typo = "components:\n  - {name: a, executable: true}\nhosts:\n  one: \"a, x\"\n";
  EXPECT_NE(problems(load(typo)).find("field 'hosts.one': no component 'x'"), std::string::npos);
}

TEST_F(PipelineHosts, NetworkProfileNeedsAnExistingInterface) {
  const std::string base = "components:\n  - {name: a, executable: true}\ndds_profile: network\n";
  EXPECT_NE(problems(load(base)).find("field 'dds_interface' is empty"), std::string::npos);
  EXPECT_NE(problems(load(base + "dds_interface: nosuchif0\n"))
                .find("field 'dds_interface': interface 'nosuchif0' does not exist on this host (it has: "),
            std::string::npos);
  EXPECT_NE(problems(load("components:\n  - {name: a, executable: true}\ndds_profile: wifi\n"))
                .find("field 'dds_profile': expected loopback or network, got 'wifi'"),
            std::string::npos);
  const auto ok = load(base + "dds_interface: lo\ndds_peers: \"10.0.0.1, 10.0.0.2\"\ndds_lease_s: 4\n");
  ASSERT_TRUE(ok.problems.empty()) << problems(ok);
  ASSERT_TRUE(ok.pipeline.network.has_value());
  EXPECT_EQ(ok.pipeline.network->interface, "lo");
  EXPECT_EQ(ok.pipeline.network->peers, (std::vector<std::string>{"10.0.0.1", "10.0.0.2", "127.0.0.1"}))
      << "this host's own address is added";
  EXPECT_DOUBLE_EQ(ok.pipeline.network->lease_s, 4.0);
  // Only the other host given: this host's own address is added, or its processes would not find
  // each other (measured over veth).
  const auto own = load(base + "dds_interface: lo\ndds_peers: \"10.0.0.2\"\n");
  ASSERT_TRUE(own.problems.empty()) << problems(own);
  EXPECT_EQ(own.pipeline.network->peers, (std::vector<std::string>{"10.0.0.2", "127.0.0.1"}));
  EXPECT_EQ(runtime::interface_ipv4_address("lo"), "127.0.0.1");
  EXPECT_FALSE(runtime::interface_ipv4_address("nosuchif0").has_value());
  // Loopback (the default) needs none of it.
  EXPECT_FALSE(load("components:\n  - {name: a, executable: true}\n").pipeline.network.has_value());
}

TEST(DdsNetworkProfile, UnicastPeersNeedParticipantIndexAndNoMulticast) {
  runtime::DdsNetworkProfile profile;
  profile.interface = "eth0";
  profile.peers = {"10.0.0.1", "10.0.0.2", "10.0.0.1"};
  const std::string xml = runtime::network_dds_config(profile);
  EXPECT_NE(xml.find("<NetworkInterface name=\"eth0\"/>"), std::string::npos) << xml;
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos);
  EXPECT_NE(xml.find("<Peers><Peer address=\"10.0.0.1\"/><Peer address=\"10.0.0.2\"/></Peers>"), std::string::npos)
      << "each peer once";
  EXPECT_NE(xml.find("<LeaseDuration>10000ms</LeaseDuration>"), std::string::npos);
}

TEST(DdsNetworkProfile, NoPeersMeansMulticastDiscovery) {
  runtime::DdsNetworkProfile profile;
  profile.interface = "eth0";
  const std::string xml = runtime::network_dds_config(profile);
  EXPECT_NE(xml.find("<AllowMulticast>spdp</AllowMulticast>"), std::string::npos) << xml;
  EXPECT_EQ(xml.find("<Peers>"), std::string::npos);
}

TEST(DdsNetworkProfile, RejectsWhatCannotGoIntoTheXml) {
  runtime::DdsNetworkProfile profile;
  EXPECT_THROW(runtime::network_dds_config(profile), std::invalid_argument);  // no interface
  profile.interface = "eth0\"/><x";
  EXPECT_THROW(runtime::network_dds_config(profile), std::invalid_argument);
  profile.interface = "eth0";
  profile.lease_s = 0.0;
  EXPECT_THROW(runtime::network_dds_config(profile), std::invalid_argument);
}

TEST(DdsNetworkProfile, SplitListTakesCommasAndSpaces) {
  EXPECT_EQ(runtime::split_list(" a, b  c,,d "), (std::vector<std::string>{"a", "b", "c", "d"}));
  EXPECT_TRUE(runtime::split_list("").empty());
}

// The XML is accepted by Cyclone itself: a participant comes up on it (loopback interface, so it
// works on any machine).
TEST(DdsNetworkProfile, CycloneAcceptsTheXml) {
  runtime::DdsNetworkProfile profile;
  profile.interface = "lo";
  profile.peers = {"127.0.0.1"};
  const int domain = test::exclusive_domain_id();
  const dds_entity_t created =
      dds_create_domain(static_cast<dds_domainid_t>(domain), runtime::network_dds_config(profile).c_str());
  ASSERT_GT(created, 0) << dds_strretcode(created);
  dds_delete(created);
}

}  // namespace
}  // namespace heslam
