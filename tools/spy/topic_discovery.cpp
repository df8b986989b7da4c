// Snapshot of the domain's endpoints from the builtin discovery topics.
#include "tools/spy/topic_discovery.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <thread>

#include "runtime/entity.hpp"

namespace heslam {

namespace {

// Loans this many builtin samples per read: more endpoints than a heslam domain ever has.
constexpr std::size_t kMaxEndpoints = 4096;
constexpr std::size_t kGuidPrefixBytes = 12;  // participant part of a GUID

std::string hex(const unsigned char* bytes, std::size_t count) {
  std::string text;
  char byte[4];
  for (std::size_t i = 0; i < count; ++i) {
    std::snprintf(byte, sizeof(byte), "%02x", bytes[i]);
    text += byte;
  }
  return text;
}

std::string guid_prefix(const dds_guid_t& guid) { return hex(guid.v, kGuidPrefixBytes); }

// Reads all alive samples of a builtin reader (loaned) and calls fn(sample) for each.
template <typename Sample, typename Fn>
void read_alive(dds_entity_t reader, Fn fn) {
  std::vector<void*> samples(kMaxEndpoints, nullptr);
  std::vector<dds_sample_info_t> infos(kMaxEndpoints);
  const dds_return_t n = dds_read_mask(reader, samples.data(), infos.data(), kMaxEndpoints, kMaxEndpoints,
                                       DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE);
  if (n <= 0) return;
  for (dds_return_t i = 0; i < n; ++i) {
    if (infos[i].valid_data) fn(*static_cast<const Sample*>(samples[i]));
  }
  dds_return_loan(reader, samples.data(), n);
}

// Cyclone announces the process id and name as participant properties.
std::string describe_participant(const dds_builtintopic_participant_t& participant) {
  char* pid = nullptr;
  char* name = nullptr;
  std::string text;
  if (participant.qos != nullptr && dds_qget_prop(participant.qos, "__Pid", &pid)) {
    text.append("pid ").append(pid);
  }
  if (participant.qos != nullptr && dds_qget_prop(participant.qos, "__ProcessName", &name)) {
    if (!text.empty()) text.append(" ");
    text.append(name);
  }
  dds_free(pid);
  dds_free(name);
  return text.empty() ? guid_prefix(participant.key) : text;
}

}  // namespace

std::vector<DiscoveredEndpoint> discover_endpoints(const runtime::Participant& participant,
                                                   std::chrono::milliseconds wait) {
  const dds_entity_t handle = participant.handle();
  const runtime::Entity participants(
      runtime::check_dds(dds_create_reader(handle, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr),
                         "discovery: cannot read DCPSParticipant"));
  const runtime::Entity publications(
      runtime::check_dds(dds_create_reader(handle, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr),
                         "discovery: cannot read DCPSPublication"));
  const runtime::Entity subscriptions(
      runtime::check_dds(dds_create_reader(handle, DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr, nullptr),
                         "discovery: cannot read DCPSSubscription"));
  std::this_thread::sleep_for(wait);

  dds_guid_t own{};
  dds_get_guid(handle, &own);
  const std::string own_prefix = guid_prefix(own);

  std::map<std::string, std::string> process_of;  // participant GUID prefix -> description
  read_alive<dds_builtintopic_participant_t>(participants.get(), [&](const dds_builtintopic_participant_t& p) {
    process_of[guid_prefix(p.key)] = describe_participant(p);
  });

  std::vector<DiscoveredEndpoint> endpoints;
  auto collect = [&](bool is_writer) {
    return [&, is_writer](const dds_builtintopic_endpoint_t& endpoint) {
      const std::string prefix = guid_prefix(endpoint.participant_key);
      if (prefix == own_prefix) return;
      DiscoveredEndpoint out;
      out.is_writer = is_writer;
      out.topic = endpoint.topic_name != nullptr ? endpoint.topic_name : "";
      out.type = endpoint.type_name != nullptr ? endpoint.type_name : "";
      out.guid = hex(endpoint.key.v, sizeof(endpoint.key.v));
      const auto process = process_of.find(prefix);
      out.participant = process != process_of.end() ? process->second : prefix;
      out.qos = read_endpoint_qos(endpoint.qos, is_writer);
      endpoints.push_back(std::move(out));
    };
  };
  read_alive<dds_builtintopic_endpoint_t>(publications.get(), collect(true));
  read_alive<dds_builtintopic_endpoint_t>(subscriptions.get(), collect(false));
  std::sort(endpoints.begin(), endpoints.end(), [](const DiscoveredEndpoint& a, const DiscoveredEndpoint& b) {
    if (a.topic != b.topic) return a.topic < b.topic;
    if (a.is_writer != b.is_writer) return a.is_writer;
    return a.guid < b.guid;
  });
  return endpoints;
}

}  // namespace heslam
