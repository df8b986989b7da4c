// DDS Security (authentication, access control, encryption) for a participant: the Cyclone
// <Security> configuration of one identity made by `heslam-security init DIR` (docs/security.md).
// An identity folder DIR/identities/NAME holds cert.pem, key.pem and permissions.p7s; the CA
// certificates and the governance come from DIR/ca and DIR/governance.p7s.
#pragma once

#include <filesystem>
#include <string>

namespace heslam::runtime {

// The environment variable naming the identity folder a process runs as (the supervisor sets it per
// component in a secure pipeline); unset or empty: plain DDS.
inline constexpr const char* kSecurityEnv = "HESLAM_SECURITY";

// Highest domain id a secure participant can use: Cyclone 0.10's access control parser rejects ids
// above 230 in governance and permissions documents (the runtime otherwise allows up to 232).
inline constexpr int kMaxSecureDomainId = 230;

// The identity folder of this process from $HESLAM_SECURITY; empty when unset.
std::filesystem::path security_identity_from_env();

// The folders and files of a secure run made by heslam-security (layout above).
struct SecurityFiles {
  std::filesystem::path identity_ca;     // DIR/ca/identity_ca.pem
  std::filesystem::path permissions_ca;  // DIR/ca/permissions_ca.pem
  std::filesystem::path governance;      // DIR/governance.p7s (signed)
  std::filesystem::path certificate;     // DIR/identities/NAME/cert.pem
  std::filesystem::path private_key;     // DIR/identities/NAME/key.pem
  std::filesystem::path permissions;     // DIR/identities/NAME/permissions.p7s (signed)
};

// The files of identity `name` under the security folder `dir`.
SecurityFiles security_files(const std::filesystem::path& dir, const std::string& name);
// The files of an identity folder (DIR/identities/NAME).
SecurityFiles security_files(const std::filesystem::path& identity_dir);

// Throws std::runtime_error with one line naming the first missing file and how to make it.
void check_security_files(const SecurityFiles& files);

// The Cyclone XML fragment (<CycloneDDS><Domain id="any"><Security>...) of an identity, with the
// plugin libraries of this build's Cyclone; appended to the domain configuration. Checks the files
// first (check_security_files); throws when this build found no Cyclone security plugins.
std::string security_config_xml(const SecurityFiles& files);

// The folder of Cyclone's security plugins found at build time ("" if none was found).
const std::string& security_plugin_dir();

}  // namespace heslam::runtime
