// The image transport option: --image-transport/--image-domain on every program, the
// pipeline fields image_transport/image_domain/roudi_config, and one clear line for each mistake.
// No RouDi needed: the SHM participant itself is exercised by heslam_shm_pipeline_test.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime/args.hpp"
#include "runtime/image_transport.hpp"
#include "runtime/supervisor/pipeline.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

using runtime::ImageTransport;

runtime::CommonArgs parse(std::vector<const char*> argv) {
  argv.insert(argv.begin(), "heslam-frontend");
  return runtime::parse_common_args(static_cast<int>(argv.size()), argv.data(), "frontend");
}

std::string error_of(std::vector<const char*> argv) {
  try {
    parse(std::move(argv));
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(ImageTransport, NamesRoundTripAndOthersAreRejected) {
  EXPECT_EQ(runtime::parse_image_transport("udp"), ImageTransport::kUdp);
  EXPECT_EQ(runtime::parse_image_transport("shm"), ImageTransport::kShm);
  EXPECT_EQ(runtime::parse_image_transport("SHM"), std::nullopt);
  EXPECT_EQ(runtime::parse_image_transport(""), std::nullopt);
  EXPECT_EQ(runtime::to_string(ImageTransport::kShm), "shm");
  EXPECT_EQ(runtime::to_string(ImageTransport::kUdp), "udp");
}

TEST(ImageTransport, UdpIsTheDefaultAndShmNeedsItsOwnDomain) {
  const runtime::CommonArgs plain = parse({"--domain", "5"});
  EXPECT_EQ(plain.image_transport, ImageTransport::kUdp);
  const runtime::CommonArgs shm = parse({"--domain", "5", "--image-transport", "shm", "--image-domain", "6"});
  EXPECT_EQ(shm.image_transport, ImageTransport::kShm);
  EXPECT_EQ(shm.image_domain_id, 6);
  EXPECT_TRUE(shm.rest.empty());

  EXPECT_EQ(error_of({"--image-transport", "tcp"}), "--image-transport: expected udp or shm, got 'tcp'");
  EXPECT_EQ(error_of({"--domain", "5", "--image-transport", "shm"}),
            "--image-transport shm: needs --image-domain N, a domain other than --domain (5)");
  EXPECT_EQ(error_of({"--domain", "5", "--image-transport", "shm", "--image-domain", "5"}),
            "--image-transport shm: needs --image-domain N, a domain other than --domain (5)");
  EXPECT_NE(error_of({"--image-domain", "999"}).find("--image-domain: expected an integer in [0, 232]"),
            std::string::npos);
}

// The UDP image participant is the component's own: nothing new is created, no RouDi is asked for.
TEST(ImageTransport, UdpImageParticipantIsTheMainOne) {
  runtime::Participant main({.domain_id = test::exclusive_domain_id(), .dds_config = ""});
  runtime::ImageParticipant images(main, ImageTransport::kUdp, -1, "");
  EXPECT_EQ(&images.get(), &main);
  EXPECT_FALSE(images.separate_domain());
}

class ImageTransportPipeline : public ::testing::Test {
 protected:
  supervisor::LoadResult load(const std::string& fields, const supervisor::PipelineOverrides& overrides = {}) {
    const auto folder = dir_.path() / "pipelines";
    std::filesystem::create_directories(folder);
    std::filesystem::create_directories(dir_.path() / "iceoryx");
    std::ofstream(dir_.path() / "iceoryx" / "roudi.toml") << "[general]\nversion = 1\n";
    const auto file = folder / "p.yaml";
    std::ofstream(file) << "domain: 7\n" << fields << "components:\n  - {name: replay, executable: true}\n";
    return supervisor::load_pipeline(file, overrides, "/bin");
  }
  static std::string problems(const supervisor::LoadResult& result) {
    std::string text;
    for (const auto& problem : result.problems) text += problem + "\n";
    return text;
  }
  test::ScratchDir dir_{"image_transport_pipeline"};
};

TEST_F(ImageTransportPipeline, DefaultsToUdp) {
  const auto result = load("");
  ASSERT_TRUE(result.problems.empty()) << problems(result);
  EXPECT_EQ(result.pipeline.image_transport, ImageTransport::kUdp);
}

TEST_F(ImageTransportPipeline, ShmTakesTheNextDomainAndTheRepositoryRoudiConfig) {
  const auto result = load("image_transport: shm\n");
  ASSERT_TRUE(result.problems.empty()) << problems(result);
  EXPECT_EQ(result.pipeline.image_transport, ImageTransport::kShm);
  EXPECT_EQ(result.pipeline.image_domain_id, 8);
  EXPECT_EQ(result.pipeline.roudi_config, (dir_.path() / "iceoryx" / "roudi.toml").lexically_normal());
}

TEST_F(ImageTransportPipeline, CommandLineOverridesTheFile) {
  supervisor::PipelineOverrides overrides;
  overrides.image_transport = "shm";
  overrides.image_domain_id = 30;
  const auto result = load("image_transport: udp\n", overrides);
  ASSERT_TRUE(result.problems.empty()) << problems(result);
  EXPECT_EQ(result.pipeline.image_transport, ImageTransport::kShm);
  EXPECT_EQ(result.pipeline.image_domain_id, 30);
}

TEST_F(ImageTransportPipeline, MistakesAreOneLineEach) {
  EXPECT_NE(problems(load("image_transport: tcp\n")).find("field 'image_transport': expected udp or shm, got 'tcp'"),
            std::string::npos);
  EXPECT_NE(problems(load("image_transport: shm\nimage_domain: 7\n"))
                .find("field 'image_domain': expected an integer in [0, 232] other than the domain (7)"),
            std::string::npos);
  EXPECT_NE(problems(load("image_transport: shm\nroudi_config: nowhere.toml\n")).find("field 'roudi_config': file"),
            std::string::npos);
  // Shared memory with DDS Security is untested: refused before the security files are even read.
  EXPECT_NE(problems(load("image_transport: shm\nsecurity: " + dir_.path().string() + "\n"))
                .find("field 'security': DDS security with image_transport shm is not supported"),
            std::string::npos);
  // image_domain with udp is accepted (read, unused): switching transport is one field.
  EXPECT_TRUE(load("image_transport: udp\nimage_domain: 9\n").problems.empty());
}

}  // namespace
}  // namespace heslam
