// heslam-occupancy's maps on request (idl/occupancy_save.idl, docs/occupancy.md "On request"): the
// request and reply types under C++ names with their Writer/Reader traits, and their topics. Apart
// from runtime/messages.hpp and runtime/topics.hpp so that only the process and its tool
// (heslam-occupancy-save) include the generated header.
#pragma once

#include <string_view>

#include "idl/occupancy_save.h"
#include "runtime/messages.hpp"
#include "runtime/topics.hpp"

namespace heslam::msg {
using OccupancySaveRequest = heslam_msg_OccupancySaveRequest;
using OccupancySaveReply = heslam_msg_OccupancySaveReply;
}  // namespace heslam::msg

namespace heslam::runtime {
template <>
struct MessageTraits<msg::OccupancySaveRequest> {
  static const dds_topic_descriptor_t* descriptor() { return &heslam_msg_OccupancySaveRequest_desc; }
  static constexpr const char* name() { return "OccupancySaveRequest"; }
};
template <>
struct MessageTraits<msg::OccupancySaveReply> {
  static const dds_topic_descriptor_t* descriptor() { return &heslam_msg_OccupancySaveReply_desc; }
  static constexpr const char* name() { return "OccupancySaveReply"; }
};
}  // namespace heslam::runtime

namespace heslam::occupancy {

inline constexpr std::string_view kSaveRequestTopic = "map/occupancy_save_request";
inline constexpr std::string_view kSaveReplyTopic = "map/occupancy_save_reply";

// Reliable, volatile, KEEP_LAST(64) (the lockstep role): tiny, never lost, never replayed to a late reader.
inline runtime::TopicSpec<msg::OccupancySaveRequest> save_request_topic(const runtime::Topics& topics) {
  return {topics.full_name(kSaveRequestTopic), runtime::QosRole::kLockstep};
}
inline runtime::TopicSpec<msg::OccupancySaveReply> save_reply_topic(const runtime::Topics& topics) {
  return {topics.full_name(kSaveReplyTopic), runtime::QosRole::kLockstep};
}

}  // namespace heslam::occupancy
