// Discovered QoS as values, and the DDS "requested vs offered" matching rules (DDS 1.4, 2.2.3).
#include "tools/spy/endpoint_qos.hpp"

#include <algorithm>
#include <cstdio>

namespace heslam {

namespace {

const char* kDurabilityNames[] = {"VOLATILE", "TRANSIENT_LOCAL", "TRANSIENT", "PERSISTENT"};
const char* kLivelinessNames[] = {"AUTOMATIC", "MANUAL_BY_PARTICIPANT", "MANUAL_BY_TOPIC"};

std::string duration(std::int64_t ns) {
  if (ns == DDS_INFINITY) return "infinite";
  char text[32];
  if (ns % 1'000'000'000 == 0) {
    std::snprintf(text, sizeof(text), "%lld s", static_cast<long long>(ns / 1'000'000'000));
  } else {
    std::snprintf(text, sizeof(text), "%.3g ms", static_cast<double>(ns) * 1e-6);
  }
  return text;
}

bool partitions_overlap(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  const std::vector<std::string> default_partition{""};
  const auto& left = a.empty() ? default_partition : a;
  const auto& right = b.empty() ? default_partition : b;
  // Exact names only: the spy does not evaluate partition wildcards.
  return std::any_of(left.begin(), left.end(), [&](const std::string& name) {
    return std::find(right.begin(), right.end(), name) != right.end();
  });
}

}  // namespace

EndpointQos read_endpoint_qos(const dds_qos_t* qos, bool is_writer) {
  EndpointQos out;
  // DDS defaults for absent policies: writers reliable, readers best effort.
  out.reliable = is_writer;
  if (qos == nullptr) return out;
  dds_reliability_kind_t reliability;
  dds_duration_t max_blocking = 0;
  if (dds_qget_reliability(qos, &reliability, &max_blocking)) {
    out.reliable = reliability == DDS_RELIABILITY_RELIABLE;
    out.max_blocking_ns = max_blocking;
  }
  dds_durability_kind_t durability;
  if (dds_qget_durability(qos, &durability)) out.durability = static_cast<int>(durability);
  dds_history_kind_t history;
  int32_t depth = 1;
  if (dds_qget_history(qos, &history, &depth)) {
    out.keep_all = history == DDS_HISTORY_KEEP_ALL;
    out.depth = depth;
  }
  dds_duration_t deadline;
  if (dds_qget_deadline(qos, &deadline)) out.deadline_ns = deadline;
  dds_liveliness_kind_t liveliness;
  dds_duration_t lease;
  if (dds_qget_liveliness(qos, &liveliness, &lease)) {
    out.liveliness = static_cast<int>(liveliness);
    out.lease_ns = lease;
  }
  dds_ownership_kind_t ownership;
  if (dds_qget_ownership(qos, &ownership)) out.exclusive_ownership = ownership == DDS_OWNERSHIP_EXCLUSIVE;
  uint32_t count = 0;
  char** names = nullptr;
  if (dds_qget_partition(qos, &count, &names)) {
    for (uint32_t i = 0; i < count; ++i) {
      out.partitions.emplace_back(names[i]);
      dds_free(names[i]);
    }
    dds_free(names);
  }
  dds_duration_t cleanup;
  dds_history_kind_t service_history;
  int32_t service_depth = 1, max_samples, max_instances, max_per_instance;
  if (dds_qget_durability_service(qos, &cleanup, &service_history, &service_depth, &max_samples, &max_instances,
                                  &max_per_instance)) {
    out.service_keep_all = service_history == DDS_HISTORY_KEEP_ALL;
    out.service_depth = service_depth;
  }
  return out;
}

std::string describe(const EndpointQos& qos, bool is_writer) {
  std::string text = qos.reliable ? "RELIABLE" : "BEST_EFFORT";
  if (qos.reliable && is_writer) text += "(max_blocking " + duration(qos.max_blocking_ns) + ")";
  text += " ";
  text += kDurabilityNames[std::clamp(qos.durability, 0, 3)];
  if (qos.durability >= 1 && is_writer) {
    text += "(late joiners get " +
            (qos.service_keep_all ? std::string("all") : "KEEP_LAST(" + std::to_string(qos.service_depth) + ")") + ")";
  }
  text += qos.keep_all ? " KEEP_ALL" : " KEEP_LAST(" + std::to_string(qos.depth) + ")";
  text += std::string(" liveliness ") + kLivelinessNames[std::clamp(qos.liveliness, 0, 2)] + "(" +
          duration(qos.lease_ns) + ")";
  if (qos.deadline_ns != DDS_INFINITY) text += " deadline " + duration(qos.deadline_ns);
  if (qos.exclusive_ownership) text += " EXCLUSIVE";
  if (!qos.partitions.empty()) {
    text += " partitions [";
    for (std::size_t i = 0; i < qos.partitions.size(); ++i) text += (i ? "," : "") + qos.partitions[i];
    text += "]";
  }
  return text;
}

std::vector<std::string> incompatibilities(const EndpointQos& writer, const EndpointQos& reader) {
  std::vector<std::string> reasons;
  if (reader.reliable && !writer.reliable)
    reasons.push_back("RELIABILITY: reader requests RELIABLE, writer offers BEST_EFFORT");
  if (reader.durability > writer.durability) {
    reasons.push_back(std::string("DURABILITY: reader requests ") +
                      kDurabilityNames[std::clamp(reader.durability, 0, 3)] + ", writer offers " +
                      kDurabilityNames[std::clamp(writer.durability, 0, 3)]);
  }
  if (reader.deadline_ns < writer.deadline_ns) {
    reasons.push_back("DEADLINE: reader requests " + duration(reader.deadline_ns) + ", writer offers " +
                      duration(writer.deadline_ns));
  }
  if (reader.liveliness > writer.liveliness || reader.lease_ns < writer.lease_ns) {
    reasons.push_back(std::string("LIVELINESS: reader requests ") +
                      kLivelinessNames[std::clamp(reader.liveliness, 0, 2)] + "(" + duration(reader.lease_ns) +
                      "), writer offers " + kLivelinessNames[std::clamp(writer.liveliness, 0, 2)] + "(" +
                      duration(writer.lease_ns) + ")");
  }
  if (reader.exclusive_ownership != writer.exclusive_ownership) reasons.push_back("OWNERSHIP: kinds differ");
  if (!partitions_overlap(writer.partitions, reader.partitions)) reasons.push_back("PARTITION: no common partition");
  return reasons;
}

}  // namespace heslam
