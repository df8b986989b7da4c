// The QoS of a discovered writer or reader in plain values, its one-line description for
// `heslam-spy info`, and the DDS request/offer rules that decide whether a writer and a reader match.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <dds/dds.h>

namespace heslam {

struct EndpointQos {
  bool reliable = false;
  int durability = 0;  // 0 volatile, 1 transient-local, 2 transient, 3 persistent
  bool keep_all = false;
  std::int32_t depth = 1;            // KEEP_LAST depth
  std::int64_t max_blocking_ns = 0;  // reliable writers
  std::int64_t deadline_ns = DDS_INFINITY;
  int liveliness = 0;  // 0 automatic, 1 manual by participant, 2 manual by topic
  std::int64_t lease_ns = DDS_INFINITY;
  bool exclusive_ownership = false;
  std::vector<std::string> partitions;  // empty = the default partition ""
  // durability_service (transient-local writers: how much history a late joiner gets)
  bool service_keep_all = false;
  std::int32_t service_depth = 1;
};

// Reads the policies from a discovered endpoint's QoS (absent policies keep DDS defaults).
EndpointQos read_endpoint_qos(const dds_qos_t* qos, bool is_writer);

// e.g. "RELIABLE(max_blocking 100 ms) VOLATILE KEEP_LAST(4) liveliness AUTOMATIC(2 s)".
std::string describe(const EndpointQos& qos, bool is_writer);

// Why this writer and reader cannot match, one reason per violated policy (empty: compatible).
std::vector<std::string> incompatibilities(const EndpointQos& writer, const EndpointQos& reader);

}  // namespace heslam
