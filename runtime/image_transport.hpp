// Which transport carries the stereo image topic: loopback UDP on the pipeline's domain (default), or
// Cyclone's iceoryx shared memory on a second domain that carries the images only (docs/topics.md,
// "Image transport"). SHM is configured per Cyclone domain, and on an SHM domain the keyed
// transient-local topics lose their late-joiner history and a string-keyed writer (ComponentStatus)
// segfaults in dds_stream_write_key (docs/benchmarks.md), so only the images move.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "runtime/participant.hpp"

namespace heslam::runtime {

enum class ImageTransport { kUdp, kShm };

std::string_view to_string(ImageTransport transport);
// "udp" / "shm"; nullopt for anything else.
std::optional<ImageTransport> parse_image_transport(std::string_view text);

// The Cyclone XML that turns shared memory on for a domain (merged after the base configuration).
std::string shm_dds_config_fragment();

// True when an iox-roudi process runs on this host (/proc/*/comm). Without one, creating a
// participant on an SHM domain blocks forever inside iceoryx, so callers check first.
bool iox_roudi_running();

// The participant the image topic lives on: the component's own for UDP; for SHM a second
// participant on `image_domain_id` with shared memory enabled, created on first use. Throws one line
// when iox-roudi is not running.
class ImageParticipant {
 public:
  ImageParticipant(const Participant& main, ImageTransport transport, int image_domain_id, std::string dds_config);
  // Holds a reference to `main`: neither copied nor moved, so it cannot outlive or lose it.
  ImageParticipant(const ImageParticipant&) = delete;
  ImageParticipant& operator=(const ImageParticipant&) = delete;
  const Participant& get();
  ImageTransport transport() const { return transport_; }
  // True when the images are on a domain of their own (readers of them need a waitset that spans
  // domains: WaitSet(participant, WaitScope::kAllDomains)).
  bool separate_domain() const { return transport_ == ImageTransport::kShm; }

 private:
  const Participant& main_;
  ImageTransport transport_;
  int image_domain_id_;
  std::string dds_config_;
  std::optional<Participant> shm_;
};

}  // namespace heslam::runtime
