// What is on the domain, from DDS builtin topics (DCPSParticipant/Publication/Subscription):
// every user writer and reader with its topic, type, QoS and owning process.
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "runtime/participant.hpp"
#include "tools/spy/endpoint_qos.hpp"

namespace heslam {

struct DiscoveredEndpoint {
  bool is_writer = false;
  std::string topic;
  std::string type;
  std::string guid;         // endpoint GUID, hex
  std::string participant;  // "pid 1234 heslam-replay" when the process says so, else its GUID prefix
  EndpointQos qos;
};

// Listens to discovery for `wait`, then returns every alive endpoint of other participants,
// ordered by topic, writers first.
std::vector<DiscoveredEndpoint> discover_endpoints(const runtime::Participant& participant,
                                                   std::chrono::milliseconds wait);

}  // namespace heslam
