// Matched-writer queries for single-writer readers.
#include "runtime/writer_identity.hpp"

#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <string_view>
#include <vector>

#include "runtime/run_id.hpp"

namespace heslam::runtime {
namespace {

struct FreeEndpoint {
  void operator()(dds_builtintopic_endpoint_t* endpoint) const { dds_builtintopic_free_endpoint(endpoint); }
};
using Endpoint = std::unique_ptr<dds_builtintopic_endpoint_t, FreeEndpoint>;

Endpoint matched_endpoint(dds_entity_t reader, dds_instance_handle_t publication) {
  return Endpoint(dds_get_matched_publication_data(reader, publication));
}

// writer_of_this_run's answers, remembered per publication (instance handles are unique within a
// process): a writer asked while it was matched stays known after it left, so the samples it wrote
// just before leaving are still used.
std::mutex g_run_writers_mutex;
std::map<dds_instance_handle_t, bool> g_run_writers;

std::vector<dds_instance_handle_t> matched_publications(dds_entity_t reader) {
  std::vector<dds_instance_handle_t> handles(16);
  for (;;) {
    const dds_return_t n = dds_get_matched_publications(reader, handles.data(), handles.size());
    if (n < 0) return {};
    if (static_cast<size_t>(n) <= handles.size()) {
      handles.resize(static_cast<size_t>(n));
      return handles;
    }
    handles.resize(static_cast<size_t>(n));
  }
}

}  // namespace

bool writer_matched(dds_entity_t reader, dds_instance_handle_t publication) {
  return matched_endpoint(reader, publication) != nullptr;
}

std::string describe_writer(dds_entity_t reader, dds_instance_handle_t publication) {
  const Endpoint endpoint = matched_endpoint(reader, publication);
  if (!endpoint) return "publication handle " + std::to_string(publication);
  // 16 bytes: 12 of participant prefix (host, process, instance), 4 of entity id.
  std::string text = "GUID ";
  char hex[3];
  for (int i = 0; i < 16; ++i) {
    std::snprintf(hex, sizeof hex, "%02x", endpoint->key.v[i]);
    text += hex;
    if (i % 4 == 3 && i != 15) text += ':';
  }
  return text;
}

std::string guid_prefix_hex(const unsigned char* guid) {
  constexpr int kPrefixBytes = 12;
  std::string text;
  char hex[3];
  for (int i = 0; i < kPrefixBytes; ++i) {
    std::snprintf(hex, sizeof hex, "%02x", guid[i]);
    text += hex;
  }
  return text;
}

std::optional<std::string> writer_participant(dds_entity_t reader, dds_instance_handle_t publication) {
  const Endpoint endpoint = matched_endpoint(reader, publication);
  if (!endpoint) return std::nullopt;
  return guid_prefix_hex(endpoint->participant_key.v);
}

std::optional<std::string> writer_run_id(dds_entity_t reader, dds_instance_handle_t publication) {
  const Endpoint endpoint = matched_endpoint(reader, publication);
  if (!endpoint) return std::nullopt;
  void* value = nullptr;
  size_t size = 0;
  if (endpoint->qos == nullptr || !dds_qget_userdata(endpoint->qos, &value, &size) || value == nullptr)
    return std::string();
  const std::string_view user_data(static_cast<const char*>(value), size);
  std::string run_id;
  if (user_data.starts_with(kRunUserDataPrefix)) run_id = std::string(user_data.substr(kRunUserDataPrefix.size()));
  dds_free(value);
  return run_id;
}

bool writer_of_this_run(dds_entity_t reader, dds_instance_handle_t publication) {
  if (!run_on_one_host()) return true;
  const std::lock_guard lock(g_run_writers_mutex);
  // Every writer matched now is asked while it still can be, not only the one of this sample.
  for (const dds_instance_handle_t matched : matched_publications(reader)) {
    if (g_run_writers.contains(matched)) continue;
    const std::optional<std::string> run = writer_run_id(reader, matched);
    if (run) g_run_writers[matched] = *run == process_run_id();
  }
  const auto known = g_run_writers.find(publication);
  return known != g_run_writers.end() && known->second;
}

}  // namespace heslam::runtime
