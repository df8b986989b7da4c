// Participant: one Cyclone domain per id per process (created from the configuration the first time
// a participant on that id is made, released with its last participant), one participant on it.
#include "runtime/participant.hpp"

#include <cstdlib>
#include <map>
#include <mutex>
#include <stdexcept>
#include <utility>

#include "runtime/security.hpp"
#include "runtime/startup_notify.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::runtime {
namespace {

std::string base_config(const ParticipantOptions& options) {
  if (!options.dds_config.empty()) return options.dds_config;
  if (const char* uri = std::getenv("CYCLONEDDS_URI"); uri != nullptr && *uri != '\0') return uri;
  return default_dds_config();
}

std::filesystem::path chosen_identity(const ParticipantOptions& options) {
  return options.security_identity.empty() ? security_identity_from_env() : options.security_identity;
}

// Cyclone merges a comma-separated list of XML texts and file:// URIs, later ones adding to earlier.
std::string chosen_config(const ParticipantOptions& options) {
  const std::filesystem::path identity = chosen_identity(options);
  if (identity.empty()) return base_config(options);
  return base_config(options) + "," + security_config_xml(security_files(identity));
}

// Domains are process-wide in Cyclone; share one per id between participants.
std::shared_ptr<void> acquire_domain(int domain_id, const std::string& config) {
  static std::mutex mutex;
  static std::map<int, std::weak_ptr<void>> domains;
  std::lock_guard lock(mutex);
  if (auto existing = domains[domain_id].lock()) return existing;
  const dds_entity_t domain = dds_create_domain(static_cast<dds_domainid_t>(domain_id), config.c_str());
  if (domain == DDS_RETCODE_PRECONDITION_NOT_MET) {
    // Created outside this registry (another library in the process): use it as it is.
    return std::shared_ptr<void>(nullptr, [](void*) {});
  }
  check_dds(domain, "DDS domain " + std::to_string(domain_id) + ": cannot create domain (check the Cyclone XML)");
  std::shared_ptr<void> handle(nullptr, [domain](void*) { dds_delete(domain); });
  domains[domain_id] = handle;
  return handle;
}

}  // namespace

dds_return_t check_dds(dds_return_t ret, const std::string& what) {
  if (ret < 0) throw std::runtime_error(what + ": " + dds_strretcode(ret));
  return ret;
}

Participant::Participant(const ParticipantOptions& options) : domain_id_(options.domain_id) {
  if (options.domain_id < 0 || options.domain_id > kMaxDomainId) {
    throw std::runtime_error("DDS domain " + std::to_string(options.domain_id) + ": expected an id in [0, " +
                             std::to_string(kMaxDomainId) + "]");
  }
  const std::filesystem::path identity = chosen_identity(options);
  if (!identity.empty() && options.domain_id > kMaxSecureDomainId) {
    throw std::runtime_error("DDS domain " + std::to_string(options.domain_id) + ": DDS security supports domains 0-" +
                             std::to_string(kMaxSecureDomainId) + " (Cyclone's access control rejects higher ids)");
  }
  domain_ = acquire_domain(options.domain_id, chosen_config(options));
  const std::string secure_hint =
      identity.empty() ? std::string()
                       : " with DDS security identity " + identity.string() +
                             " (Cyclone's reason is on stderr: e.g. a certificate or permissions document not signed "
                             "by this folder's CA, or expired)";
  handle_ = check_dds(dds_create_participant(static_cast<dds_domainid_t>(options.domain_id), nullptr, nullptr),
                      "DDS domain " + std::to_string(options.domain_id) + ": cannot create participant" + secure_hint);
  // Told to heslam-supervisor, which trusts its components' status only from their participants.
  dds_guid_t guid;
  if (dds_get_guid(handle_, &guid) == DDS_RETCODE_OK) notify_supervisor_participant(guid_prefix_hex(guid.v));
}

Participant::~Participant() {
  if (handle_ > 0) dds_delete(handle_);
}

Participant::Participant(Participant&& other) noexcept
    : domain_(std::move(other.domain_)), handle_(std::exchange(other.handle_, 0)), domain_id_(other.domain_id_) {}

Participant& Participant::operator=(Participant&& other) noexcept {
  if (this != &other) {
    if (handle_ > 0) dds_delete(handle_);
    handle_ = std::exchange(other.handle_, 0);
    domain_ = std::move(other.domain_);
    domain_id_ = other.domain_id_;
  }
  return *this;
}

}  // namespace heslam::runtime
