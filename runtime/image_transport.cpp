// ImageParticipant and the iox-roudi check (why SHM is limited to the images: image_transport.hpp).
#include "runtime/image_transport.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <utility>

namespace heslam::runtime {

std::string_view to_string(ImageTransport transport) { return transport == ImageTransport::kShm ? "shm" : "udp"; }

std::optional<ImageTransport> parse_image_transport(std::string_view text) {
  if (text == "udp") return ImageTransport::kUdp;
  if (text == "shm") return ImageTransport::kShm;
  return std::nullopt;
}

std::string shm_dds_config_fragment() {
  // LogLevel warn: iceoryx's info lines ("RouDi registration") would interleave with component logs.
  return "<CycloneDDS><Domain id=\"any\"><SharedMemory><Enable>true</Enable><LogLevel>warn</LogLevel>"
         "</SharedMemory></Domain></CycloneDDS>";
}

bool iox_roudi_running() {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/proc", error)) {
    const std::string pid = entry.path().filename().string();
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream comm(entry.path() / "comm");
    std::string name;
    if (std::getline(comm, name) && name == "iox-roudi") return true;
  }
  return false;
}

ImageParticipant::ImageParticipant(const Participant& main, ImageTransport transport, int image_domain_id,
                                   std::string dds_config)
    : main_(main), transport_(transport), image_domain_id_(image_domain_id), dds_config_(std::move(dds_config)) {}

const Participant& ImageParticipant::get() {
  if (transport_ == ImageTransport::kUdp) return main_;
  if (!shm_) {
    if (image_domain_id_ < 0 || image_domain_id_ == main_.domain_id()) {
      throw std::runtime_error("image transport shm: needs --image-domain N, a domain other than the pipeline's (" +
                               std::to_string(main_.domain_id()) + ")");
    }
    if (!iox_roudi_running()) {
      throw std::runtime_error(
          "image transport shm: iox-roudi is not running (apt-get install iceoryx; heslam-supervisor starts it "
          "with config/iceoryx/roudi.toml)");
    }
    std::string base = dds_config_;
    if (base.empty()) {
      const char* uri = std::getenv("CYCLONEDDS_URI");
      base = uri != nullptr && *uri != '\0' ? std::string(uri) : default_dds_config();
    }
    // Shared memory with DDS Security is untested, so heslam-supervisor refuses that combination.
    shm_.emplace(ParticipantOptions{
        .domain_id = image_domain_id_, .dds_config = base + "," + shm_dds_config_fragment(), .security_identity = {}});
  }
  return *shm_;
}

}  // namespace heslam::runtime
