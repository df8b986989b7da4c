// The Cyclone <Security> fragment of an identity made by heslam-security, and its file checks.
#include "runtime/security.hpp"

#include <cstdlib>
#include <stdexcept>

namespace heslam::runtime {
namespace {

// Cyclone reads each document through a "file:" URI.
std::string file_uri(const std::filesystem::path& path) {
  std::string text = "file:" + std::filesystem::absolute(path).lexically_normal().string();
  std::string escaped;
  for (char c : text) {
    switch (c) {
      case '&': escaped += "&amp;"; break;
      case '<': escaped += "&lt;"; break;
      case '>': escaped += "&gt;"; break;
      case '"': escaped += "&quot;"; break;
      default: escaped += c;
    }
  }
  return escaped;
}

std::string library(const std::string& name, const std::string& init, const std::string& finalize) {
  return "<Library path=\"" + security_plugin_dir() + "/libdds_security_" + name + ".so\" initFunction=\"" + init +
         "\" finalizeFunction=\"" + finalize + "\"/>";
}

}  // namespace

const std::string& security_plugin_dir() {
  static const std::string dir = HESLAM_DDS_SECURITY_PLUGIN_DIR;
  return dir;
}

std::filesystem::path security_identity_from_env() {
  const char* value = std::getenv(kSecurityEnv);
  return value == nullptr ? std::filesystem::path() : std::filesystem::path(value);
}

SecurityFiles security_files(const std::filesystem::path& dir, const std::string& name) {
  return security_files(dir / "identities" / name);
}

SecurityFiles security_files(const std::filesystem::path& identity_dir) {
  std::filesystem::path normal = std::filesystem::absolute(identity_dir).lexically_normal();
  if (!normal.has_filename()) normal = normal.parent_path();              // "DIR/identities/NAME/"
  const std::filesystem::path root = normal.parent_path().parent_path();  // DIR/identities/NAME -> DIR
  return SecurityFiles{root / "ca" / "identity_ca.pem", root / "ca" / "permissions_ca.pem",
                       root / "governance.p7s",         identity_dir / "cert.pem",
                       identity_dir / "key.pem",        identity_dir / "permissions.p7s"};
}

void check_security_files(const SecurityFiles& files) {
  for (const auto* path : {&files.identity_ca, &files.permissions_ca, &files.governance, &files.certificate,
                           &files.private_key, &files.permissions}) {
    if (!std::filesystem::is_regular_file(*path)) {
      throw std::runtime_error("DDS security: " + path->string() +
                               " does not exist (make the folder with heslam-security init DIR; one more identity with "
                               "heslam-security add DIR NAME:PUBLISH:SUBSCRIBE)");
    }
  }
}

std::string security_config_xml(const SecurityFiles& files) {
  check_security_files(files);
  if (security_plugin_dir().empty()) {
    throw std::runtime_error(
        "DDS security: this build found no Cyclone DDS security plugins (libdds_security_auth.so); install the "
        "Cyclone DDS library with its plugins and reconfigure");
  }
  return "<CycloneDDS xmlns=\"https://cdds.io/config\"><Domain id=\"any\"><Security>"
         "<Authentication>" +
         library("auth", "init_authentication", "finalize_authentication") + "<IdentityCA>" +
         file_uri(files.identity_ca) + "</IdentityCA><IdentityCertificate>" + file_uri(files.certificate) +
         "</IdentityCertificate><PrivateKey>" + file_uri(files.private_key) +
         "</PrivateKey></Authentication>"
         "<AccessControl>" +
         library("ac", "init_access_control", "finalize_access_control") + "<PermissionsCA>" +
         file_uri(files.permissions_ca) + "</PermissionsCA><Governance>" + file_uri(files.governance) +
         "</Governance><Permissions>" + file_uri(files.permissions) +
         "</Permissions></AccessControl>"
         "<Cryptographic>" +
         library("crypto", "init_crypto", "finalize_crypto") + "</Cryptographic></Security></Domain></CycloneDDS>";
}

}  // namespace heslam::runtime
