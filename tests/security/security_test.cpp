// DDS Security. The material heslam-security makes (grants per component), and
// real secure participants over loopback, each test on its own domain: an authorised reader gets
// the images while a capture of the domain's UDP traffic finds no image bytes (and does find them in
// plain mode, so the capture is known to work); a participant without credentials, or with an
// identity from another CA, sees nothing and injects nothing; a component cannot create a writer for
// a topic it was not granted. The second participant is a process of its own (heslam-test-secure-peer).
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "loopback_capture.hpp"
#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/security.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "runtime/waitset.hpp"
#include "runtime/writer.hpp"
#include "secure_pattern.hpp"
#include "security_folder.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

// Bounds of a broken run (secure discovery is a handshake per pair: ~1 s on a loaded machine).
constexpr auto kDeliveryBound = 60s;
constexpr double kDeliveryBoundSeconds = 60.0;
// How long a participant that must see nothing listens while the other publishes at 20 Hz: several
// times a secure handshake plus first delivery between credentialed peers on this loaded machine.
constexpr double kSilenceSeconds = 6.0;

// Topics each identity may publish and subscribe, read back from its permissions document.
struct Grant {
  std::set<std::string> publish;
  std::set<std::string> subscribe;
};

std::set<std::string> topics_between(const std::string& text, const std::string& open, const std::string& close) {
  std::set<std::string> topics;
  const auto begin = text.find(open);
  if (begin == std::string::npos) return topics;
  const std::string block = text.substr(begin, text.find(close, begin) - begin);
  static const std::regex topic("<topic>([^<]*)</topic>");
  for (auto it = std::sregex_iterator(block.begin(), block.end(), topic); it != std::sregex_iterator(); ++it) {
    topics.insert((*it)[1].str());
  }
  return topics;
}

std::map<std::string, Grant> read_grants(const fs::path& dir) {
  std::map<std::string, Grant> grants;
  for (const auto& entry : fs::directory_iterator(dir / "identities")) {
    std::ifstream in(entry.path() / "permissions.xml");
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    grants[entry.path().filename().string()] = {topics_between(text, "<publish>", "</publish>"),
                                                topics_between(text, "<subscribe>", "</subscribe>")};
  }
  return grants;
}

std::unique_ptr<test::ChildProcess> start_peer(const fs::path& log_dir, const std::string& label, int domain,
                                               const std::string& mode, const fs::path& identity, double seconds) {
  std::vector<std::string> args{"--domain", std::to_string(domain), mode, "--seconds", std::to_string(seconds)};
  if (!identity.empty()) args.insert(args.end(), {"--identity", identity.string()});
  return std::make_unique<test::ChildProcess>(test::bin_dir() / "heslam-test-secure-peer", args, log_dir, label);
}

// Reads stereo frames until `enough` arrived or `seconds` passed; returns {received, with pattern}.
std::pair<int, int> read_frames(runtime::Participant& participant, double seconds, int enough) {
  runtime::Reader<msg::StereoFrame> reader(participant, runtime::Topics().stereo());
  runtime::WaitSet waitset(participant);
  waitset.attach(reader);
  int received = 0, with_pattern = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end && received < enough) {
    waitset.wait(100ms);
    for (auto& sample : reader.take()) {
      if (!sample.info.valid_data) continue;
      ++received;
      if (test::has_pattern(runtime::view(sample.sample->left))) ++with_pattern;
    }
  }
  return {received, with_pattern};
}

using test::last_line;

TEST(SecurityInit, GrantsEachTopicOnlyToTheComponentsThatNeedIt) {
  const test::ScratchDir dir("security_init");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  const auto grants = read_grants(security);
  const std::set<std::string> expected{"replay",   "frontend", "local_mapper", "loop_closer", "occupancy",
                                       "recorder", "viewer",   "ros2_bridge",  "supervisor",  "spy"};
  std::set<std::string> names;
  for (const auto& [name, grant] : grants) names.insert(name);
  EXPECT_EQ(names, expected);
  for (const char* name : {"cert.pem", "key.pem", "permissions.p7s"}) {
    EXPECT_TRUE(fs::is_regular_file(security / "identities/frontend" / name)) << name;
  }
  EXPECT_TRUE(fs::is_regular_file(security / "governance.p7s"));

  // Every topic of the table has a writer and a reader, and the single-writer topics one writer.
  const std::map<std::string, std::set<std::string>> only_writers{
      {"camera/stereo", {"replay"}},
      {"camera/calibration", {"replay"}},
      {"odometry", {"frontend"}},
      {"map/keyframes", {"frontend"}},
      {"map/keyframe_states", {"local_mapper"}},
      {"map/points", {"local_mapper"}},
      {"map/mapper_keyframes", {"local_mapper"}},
      {"loop/corrections", {"loop_closer"}},
      {"lockstep/frame_done", {"frontend"}},
      {"lockstep/turns", {"replay"}},
      {"lockstep/keyframe_done", {"local_mapper", "loop_closer"}},
      {"map/occupancy_grid", {"occupancy"}},
      {"map/dense_cloud", {"occupancy"}}};
  for (const runtime::TopicEntry& topic : runtime::all_topics()) {
    const std::string pattern = "*/" + std::string(topic.relative_name);
    std::set<std::string> writers, readers;
    for (const auto& [name, grant] : grants) {
      if (grant.publish.count(pattern) != 0) writers.insert(name);
      if (grant.subscribe.count(pattern) != 0 || grant.subscribe.count("*") != 0) readers.insert(name);
    }
    EXPECT_FALSE(writers.empty()) << topic.relative_name << ": nobody may write it";
    EXPECT_GT(readers.size(), 1u) << topic.relative_name << ": nobody but the spy may read it";
    const auto only = only_writers.find(std::string(topic.relative_name));
    if (only != only_writers.end()) {
      EXPECT_EQ(writers, only->second) << topic.relative_name;
    }
  }
  EXPECT_TRUE(grants.at("spy").publish.empty());
  EXPECT_EQ(grants.at("spy").subscribe, std::set<std::string>{"*"});
  // The status topic is every component's; the supervisor and the recorder also read it.
  for (const char* name : {"replay", "frontend", "local_mapper", "loop_closer", "recorder", "viewer", "supervisor"}) {
    EXPECT_EQ(grants.at(name).publish.count("*/system/status"), 1u) << name;
  }
}

TEST(SecurityFiles, IdentityFolderNamesTheFilesOfItsRunFolder) {
  for (const char* identity :
       {"/sec/identities/frontend", "/sec/identities/frontend/", "/sec/x/../identities/frontend"}) {
    const runtime::SecurityFiles files = runtime::security_files(identity);
    EXPECT_EQ(files.governance, fs::path("/sec/governance.p7s")) << identity;
    EXPECT_EQ(files.identity_ca, fs::path("/sec/ca/identity_ca.pem")) << identity;
    EXPECT_EQ(files.permissions_ca, fs::path("/sec/ca/permissions_ca.pem")) << identity;
    EXPECT_EQ(files.certificate.lexically_normal(), fs::path("/sec/identities/frontend/cert.pem")) << identity;
  }
}

// Positive control of the tests below: credentialed replay -> credentialed frontend, and the wire.
TEST(SecureDds, AuthorisedReaderGetsTheImagesAndTheWireCarriesNoImageBytes) {
  const int domain = test::capture_domain_id();
  const test::ScratchDir dir("secure_delivery");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  test::LoopbackCapture capture(domain);
  if (!capture.error().empty()) GTEST_SKIP() << capture.error();
  runtime::Participant participant(runtime::ParticipantOptions{domain, "", security / "identities/frontend"});
  auto peer = start_peer(dir.path(), "replay", domain, "publish-stereo", security / "identities/replay", 120);
  const auto [received, with_pattern] = read_frames(participant, kDeliveryBoundSeconds, 5);
  EXPECT_EQ(received, 5) << "the credentialed replay's frames did not arrive; peer: " << peer->out() << peer->err();
  EXPECT_EQ(with_pattern, received) << "frames arrived with other image bytes";
  std::cout << "[ figures ] secure: " << capture.datagrams() << " datagrams, " << capture.payload_bytes()
            << " payload bytes captured, " << capture.datagrams_with_pattern() << " with image bytes\n";
  EXPECT_GT(capture.payload_bytes(), 5L * 2 * test::kPatternWidth * test::kPatternHeight)
      << "the capture missed the image traffic";
  EXPECT_EQ(capture.datagrams_with_pattern(), 0) << "image bytes travel in the clear";
}

// The same exchange without security: the capture finds the image bytes, so the test above tells
// encrypted from not captured.
TEST(SecureDds, PlainModeControlTheCaptureSeesTheImageBytes) {
  const int domain = test::capture_domain_id();
  const test::ScratchDir dir("plain_delivery");
  test::LoopbackCapture capture(domain);
  if (!capture.error().empty()) GTEST_SKIP() << capture.error();
  runtime::Participant participant(runtime::ParticipantOptions{domain, ""});
  auto peer = start_peer(dir.path(), "replay", domain, "publish-stereo", "", 120);
  const auto [received, with_pattern] = read_frames(participant, kDeliveryBoundSeconds, 5);
  EXPECT_EQ(received, 5) << peer->err();
  EXPECT_EQ(with_pattern, received);
  std::cout << "[ figures ] plain: " << capture.datagrams() << " datagrams, " << capture.datagrams_with_pattern()
            << " with image bytes\n";
  EXPECT_GT(capture.datagrams_with_pattern(), 0);
}

TEST(SecureDds, ParticipantWithoutCredentialsSeesNoData) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("no_credentials_read");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  runtime::Participant plain(runtime::ParticipantOptions{domain, ""});
  auto peer = start_peer(dir.path(), "replay", domain, "publish-stereo", security / "identities/replay", 120);
  const auto [received, with_pattern] = read_frames(plain, kSilenceSeconds, 1);
  EXPECT_EQ(received, 0) << "a participant without credentials received secure frames";
  (void)with_pattern;
  EXPECT_EQ(peer->wait(0ms), std::nullopt) << "the publisher ended early: " << peer->err();
}

// The hostile tests' stray frame (seq far ahead) and a 100 m loop correction, from a participant
// without credentials: a credentialed frontend / mapper receives neither.
TEST(SecureDds, ParticipantWithoutCredentialsCannotInject) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("no_credentials_write");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  runtime::Participant secure(runtime::ParticipantOptions{domain, "", security / "identities/local_mapper"});
  runtime::Reader<msg::LoopCorrection> corrections(secure, runtime::Topics().loop_corrections());
  auto frames = start_peer(dir.path(), "plain_replay", domain, "publish-stereo", "", 120);
  auto injector = start_peer(dir.path(), "plain_loop", domain, "publish-correction", "", 120);
  // This process is the mapper (it may not read images); the frontend is a process of its own.
  auto frontend =
      start_peer(dir.path(), "frontend", domain, "read-stereo", security / "identities/frontend", kSilenceSeconds);
  std::this_thread::sleep_for(std::chrono::duration<double>(kSilenceSeconds));
  EXPECT_TRUE(corrections.take().empty()) << "a correction from a participant without credentials arrived";
  const auto code = frontend->wait(kDeliveryBound);
  ASSERT_EQ(code, 0) << frontend->err();
  EXPECT_EQ(last_line(frontend->out()), "peer read-stereo: received 0, 0 with the pattern");
}

// Credentials of another deployment (another CA): authentication fails, nothing is exchanged.
TEST(SecureDds, IdentityFromAnotherCaIsNotAuthenticated) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("other_ca");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  const fs::path other = test::make_security_folder(dir.path() / "other", dir.path());
  runtime::Participant participant(runtime::ParticipantOptions{domain, "", security / "identities/frontend"});
  auto peer = start_peer(dir.path(), "foreign_replay", domain, "publish-stereo", other / "identities/replay", 120);
  const auto [received, with_pattern] = read_frames(participant, kSilenceSeconds, 1);
  (void)with_pattern;
  EXPECT_EQ(received, 0) << "frames from an identity of another CA arrived";
  EXPECT_EQ(peer->wait(0ms), std::nullopt) << "the foreign publisher ended early: " << peer->err();
}

// Valid credentials, no permission: the frontend may not write images, calibration or corrections;
// the spy may write nothing; each may create what it was granted.
TEST(SecureDds, WritersOfTopicsNotGrantedAreRefused) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("not_granted");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  runtime::Participant frontend(runtime::ParticipantOptions{domain, "", security / "identities/frontend"});
  const runtime::Topics topics;
  EXPECT_THROW(runtime::Writer<msg::StereoFrame>(frontend, topics.stereo()), std::runtime_error);
  EXPECT_THROW(runtime::Writer<msg::StereoCalibration>(frontend, topics.calibration()), std::runtime_error);
  EXPECT_THROW(runtime::Writer<msg::LoopCorrection>(frontend, topics.loop_corrections()), std::runtime_error);
  EXPECT_THROW(runtime::Writer<msg::KeyframeState>(frontend, topics.keyframe_states()), std::runtime_error);
  EXPECT_THROW(runtime::Reader<msg::LoopCorrection>(frontend, topics.loop_corrections()), std::runtime_error);
  EXPECT_NO_THROW(runtime::Writer<msg::Odometry>(frontend, topics.odometry()));
  EXPECT_NO_THROW(runtime::Writer<msg::Keyframe>(frontend, topics.keyframes()));
  EXPECT_NO_THROW(runtime::Reader<msg::StereoFrame>(frontend, topics.stereo()));
  try {
    runtime::Writer<msg::StereoFrame> refused(frontend, topics.stereo());
  } catch (const std::runtime_error& error) {
    std::cout << "refused as: " << error.what() << "\n";
    EXPECT_NE(std::string(error.what()).find("heslam/camera/stereo"), std::string::npos) << error.what();
  }
}

// init --namespace robot1: the grants hold under robot1 only.
TEST(SecureDds, NamespacePinnedGrantsHoldInThatNamespaceOnly) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("pinned_namespace");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path(), {"--namespace", "robot1"});
  runtime::Participant replay(runtime::ParticipantOptions{domain, "", security / "identities/replay"});
  EXPECT_NO_THROW(runtime::Writer<msg::StereoFrame>(replay, runtime::Topics("robot1").stereo()));
  EXPECT_THROW(runtime::Writer<msg::StereoFrame>(replay, runtime::Topics("robot2").stereo()), std::runtime_error);
  EXPECT_THROW(runtime::Writer<msg::StereoFrame>(replay, runtime::Topics().stereo()), std::runtime_error);
}

TEST(SecureDds, SpyIdentityReadsEverythingAndWritesNothing) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("spy_grant");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  runtime::Participant spy(runtime::ParticipantOptions{domain, "", security / "identities/spy"});
  const runtime::Topics topics;
  EXPECT_NO_THROW(runtime::Reader<msg::StereoFrame>(spy, topics.stereo()));
  EXPECT_NO_THROW(runtime::Reader<msg::LoopCorrection>(spy, topics.loop_corrections()));
  EXPECT_NO_THROW(runtime::Reader<msg::ComponentStatus>(spy, topics.status()));
  EXPECT_THROW(runtime::Writer<msg::ComponentStatus>(spy, topics.status()), std::runtime_error);
  EXPECT_THROW(runtime::Writer<msg::StereoFrame>(spy, topics.stereo()), std::runtime_error);
}

// The same refusal in a process of its own, as a misbehaving component would meet it.
TEST(SecureDds, ComponentWithoutPermissionCannotPublishImages) {
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("peer_not_granted");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  auto peer = start_peer(dir.path(), "frontend_writes", domain, "publish-stereo", security / "identities/frontend", 1);
  ASSERT_EQ(peer->wait(kDeliveryBound), 3) << peer->out() << peer->err();
  EXPECT_NE(last_line(peer->out()).find("peer publish-stereo: refused: topic 'heslam/camera/stereo'"),
            std::string::npos)
      << peer->out();
}

// A permissions document edited after signing (the frontend granting itself the images) fails the
// signature check: no participant.
TEST(SecureDds, TamperedPermissionsAreRejected) {
  const test::ScratchDir dir("tampered");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  const fs::path signed_document = security / "identities/frontend/permissions.p7s";
  std::ifstream in(signed_document);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  in.close();
  const std::string granted = "<topic>*/odometry</topic>";
  const auto at = text.find(granted);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, granted.size(), "<topic>*/camera/stereo</topic>");
  std::ofstream(signed_document) << text;
  EXPECT_THROW(runtime::Participant(
                   runtime::ParticipantOptions{test::exclusive_domain_id(), "", security / "identities/frontend"}),
               std::runtime_error);
}

TEST(SecureDds, MissingIdentityFileIsOneClearError) {
  const test::ScratchDir dir("missing_identity");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  fs::remove(security / "identities/frontend/key.pem");
  try {
    runtime::Participant participant(
        runtime::ParticipantOptions{test::exclusive_domain_id(), "", security / "identities/frontend"});
    FAIL() << "created a secure participant without its key";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("identities/frontend/key.pem does not exist"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace heslam
