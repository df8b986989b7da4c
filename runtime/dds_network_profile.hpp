// The Cyclone DDS "network" profile: the same tuning as the built-in loopback XML
// (config/cyclonedds.xml), but on a real interface chosen by name, with unicast peers or multicast
// discovery, so the processes of one run can sit on several hosts (docs/deployment.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace heslam::runtime {

struct DdsNetworkProfile {
  // Interface by name ("eth0", "veth-a"); Cyclone 0.10 sends and receives only on it.
  std::string interface;
  // Unicast discovery: the addresses (or host names) of EVERY host of the run, this one included
  // (a process finds the others on its own host through its own address too: without it, the
  // processes of one host do not find each other; measured, docs/deployment.md). The supervisor adds
  // this host's address itself. Empty: multicast discovery on the interface (SPDP only; data stays
  // unicast).
  std::vector<std::string> peers;
  // A host silent this long is declared gone (its readers/writers removed). Longer than the
  // loopback 2 s so a short link outage (a Wi-Fi hiccup, a cable replugged) does not drop the
  // matches: reliable data then simply resumes; see docs/deployment.md.
  double lease_s = 10.0;
};

// Lease bounds: Cyclone needs > 0; a lease of hours would keep dead hosts' endpoints for hours.
inline constexpr double kMinLeaseS = 0.5;
inline constexpr double kMaxLeaseS = 600.0;

// Splits "a, b c" (commas and/or spaces) into ["a", "b", "c"].
std::vector<std::string> split_list(const std::string& text);

// The Cyclone XML of the profile. Throws std::invalid_argument for an empty interface name, a
// lease out of [kMinLeaseS, kMaxLeaseS] or a peer with characters XML or Cyclone cannot take.
std::string network_dds_config(const DdsNetworkProfile& profile);

// The interface's first IPv4 address ("10.0.0.1"), or nullopt when it has none.
std::optional<std::string> interface_ipv4_address(const std::string& name);

// nullopt when the interface exists on this host; else one line naming it and the ones that exist
// ("interface 'eht0' does not exist on this host (it has: lo, eth0)").
std::optional<std::string> check_network_interface(const std::string& name);

}  // namespace heslam::runtime
