// A DDS domain participant on domain N, configured from the project's loopback Cyclone XML
// (config/cyclonedds.xml, compiled in) unless the caller or $CYCLONEDDS_URI says otherwise; with a
// DDS Security identity (runtime/security.hpp) when one is given or $HESLAM_SECURITY names one.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include <dds/dds.h>

namespace heslam::runtime {

// Highest usable domain id (Cyclone derives UDP ports from it).
inline constexpr int kMaxDomainId = 232;

struct ParticipantOptions {
  int domain_id = 0;
  // Cyclone configuration: XML text or "file://path". Empty: $CYCLONEDDS_URI when set, else the
  // project's tuned loopback XML (config/cyclonedds.xml embedded at build time).
  std::string dds_config;
  // DDS Security identity folder (DIR/identities/NAME from heslam-security init): its <Security>
  // section is added to the configuration. Empty: $HESLAM_SECURITY; plain DDS when that is unset too.
  // The domain is created once per id per process, so every participant of a process on one domain
  // has the identity of the first.
  std::filesystem::path security_identity = {};
};

// The XML of config/cyclonedds.xml as built into this binary.
const std::string& default_dds_config();

class Participant {
 public:
  // Throws std::runtime_error ("DDS domain 7: cannot create participant: <reason>") on failure.
  explicit Participant(const ParticipantOptions& options = {});
  ~Participant();
  Participant(Participant&& other) noexcept;
  Participant& operator=(Participant&& other) noexcept;
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  dds_entity_t handle() const { return handle_; }
  int domain_id() const { return domain_id_; }

 private:
  std::shared_ptr<void> domain_;  // keeps the process-wide domain (created once per id) alive
  dds_entity_t handle_ = 0;
  int domain_id_ = 0;
};

// Throws std::runtime_error("<what>: <dds_strretcode(ret)>") when ret < 0; returns ret otherwise.
dds_return_t check_dds(dds_return_t ret, const std::string& what);

}  // namespace heslam::runtime
