// The one-line message for a sample from a build with another message schema.
#include "runtime/reader.hpp"

namespace heslam::runtime {

std::string schema_mismatch_message(const std::string& topic, uint32_t received_version) {
  return "topic '" + topic + "': dropped a sample with message schema version " + std::to_string(received_version) +
         ", this build has version " + std::to_string(msg::kSchemaVersion) +
         " (rebuild every heslam process from the same tree)";
}

}  // namespace heslam::runtime
