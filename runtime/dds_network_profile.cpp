// Builds the network profile's Cyclone XML; the tuning values are the loopback file's
// (config/cyclonedds.xml, measured in shared/notes/cyclonedds-0.10-findings.md).
#include "runtime/dds_network_profile.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>

#include <set>
#include <sstream>
#include <stdexcept>

namespace heslam::runtime {
namespace {

// Interface names and peers go into XML attributes: refuse what would need escaping rather than
// escape it (no real interface or host name contains these).
bool safe_attribute(const std::string& text) {
  return !text.empty() && text.find_first_of("<>&\"' \t\n") == std::string::npos;
}

// Unicast discovery probes MaxAutoParticipantIndex+1 ports per peer; 50 processes per host and
// domain (the loopback default 9 is too few for a full pipeline plus tools, finding 9).
constexpr int kMaxAutoParticipantIndex = 50;

}  // namespace

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  for (char c : text + ",") {
    if (c == ',' || c == ' ' || c == '\t') {
      if (!item.empty()) items.push_back(item);
      item.clear();
    } else {
      item += c;
    }
  }
  return items;
}

std::string network_dds_config(const DdsNetworkProfile& profile) {
  if (!safe_attribute(profile.interface)) {
    throw std::invalid_argument("network interface: expected an interface name such as eth0, got '" +
                                profile.interface + "'");
  }
  if (!(profile.lease_s >= kMinLeaseS && profile.lease_s <= kMaxLeaseS)) {
    std::ostringstream text;
    text << "lease: expected seconds in [" << kMinLeaseS << ", " << kMaxLeaseS << "], got " << profile.lease_s;
    throw std::invalid_argument(text.str());
  }
  for (const std::string& peer : profile.peers) {
    if (!safe_attribute(peer))
      throw std::invalid_argument("peer: expected an address or host name, got '" + peer + "'");
  }
  const bool unicast = !profile.peers.empty();
  const long lease_ms = static_cast<long>(profile.lease_s * 1000.0 + 0.5);
  std::ostringstream xml;
  xml << "<CycloneDDS xmlns=\"https://cdds.io/config\"><Domain id=\"any\">\n"
      << "  <General>\n"
      << "    <Interfaces><NetworkInterface name=\"" << profile.interface << "\"/></Interfaces>\n"
      // Peers: no multicast at all (many networks drop it). Multicast: only for discovery, data
      // goes unicast to the one host that reads it.
      << "    <AllowMulticast>" << (unicast ? "false" : "spdp") << "</AllowMulticast>\n"
      << "    <MaxMessageSize>65000B</MaxMessageSize>\n"
      << "    <FragmentSize>62000B</FragmentSize>\n"
      << "  </General>\n"
      << "  <Discovery>\n";
  if (unicast) {
    // Without ParticipantIndex auto, unicast peers find nothing (finding 9).
    xml << "    <ParticipantIndex>auto</ParticipantIndex>\n"
        << "    <MaxAutoParticipantIndex>" << kMaxAutoParticipantIndex << "</MaxAutoParticipantIndex>\n"
        << "    <Peers>";
    std::set<std::string> seen;
    for (const std::string& peer : profile.peers) {
      if (seen.insert(peer).second) xml << "<Peer address=\"" << peer << "\"/>";
    }
    xml << "</Peers>\n";
  }
  xml << "    <LeaseDuration>" << lease_ms << "ms</LeaseDuration>\n"
      << "  </Discovery>\n"
      << "  <Internal>\n"
      << "    <SocketReceiveBufferSize max=\"4MB\"/>\n"
      << "    <Watermarks><WhcHigh>8MB</WhcHigh></Watermarks>\n"
      << "  </Internal>\n"
      << "</Domain></CycloneDDS>\n";
  return xml.str();
}

std::optional<std::string> interface_ipv4_address(const std::string& name) {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return std::nullopt;
  std::optional<std::string> address;
  for (const ifaddrs* entry = list; entry != nullptr && !address; entry = entry->ifa_next) {
    if (entry->ifa_addr == nullptr || entry->ifa_addr->sa_family != AF_INET || name != entry->ifa_name) continue;
    char text[INET_ADDRSTRLEN] = {};
    const auto* ipv4 = reinterpret_cast<const sockaddr_in*>(entry->ifa_addr);
    if (inet_ntop(AF_INET, &ipv4->sin_addr, text, sizeof text) != nullptr) address = text;
  }
  freeifaddrs(list);
  return address;
}

std::optional<std::string> check_network_interface(const std::string& name) {
  if (!name.empty() && if_nametoindex(name.c_str()) != 0) return std::nullopt;
  std::set<std::string> names;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) == 0) {
    for (const ifaddrs* entry = list; entry != nullptr; entry = entry->ifa_next) names.insert(entry->ifa_name);
    freeifaddrs(list);
  }
  std::string have;
  for (const std::string& existing : names) have += (have.empty() ? "" : ", ") + existing;
  return "interface '" + name + "' does not exist on this host (it has: " + (have.empty() ? "none" : have) + ")";
}

}  // namespace heslam::runtime
