// Resolving a TOPIC argument against the topic table (runtime/topics.hpp), and calling a generic
// function with the compiled message type of that topic.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

#include "runtime/messages.hpp"
#include "runtime/qos.hpp"
#include "runtime/topics.hpp"

namespace heslam {

struct ResolvedTopic {
  std::string full_name;  // e.g. "heslam/camera/stereo"
  std::string type_name;  // MessageTraits<T>::name(), e.g. "StereoFrame"
  runtime::QosRole role;  // the role its writers use
};

// "camera/stereo" -> under `ns`; "robot2/camera/stereo" -> as given (any namespace). Throws
// "topic 'X': not a heslam topic (known: camera/stereo, ...)" for names outside the table.
ResolvedTopic resolve_topic(const std::string& topic, const std::string& ns);

// Calls fn(std::type_identity<T>{}) for the message type T whose name is type_name.
template <typename Fn>
void with_message_type(std::string_view type_name, Fn&& fn) {
  bool found = false;
  auto visit = [&]<typename T>(std::type_identity<T> tag) {
    if (!found && type_name == runtime::MessageTraits<T>::name()) {
      found = true;
      fn(tag);
    }
  };
  visit(std::type_identity<msg::StereoFrame>{});
  visit(std::type_identity<msg::StereoCalibration>{});
  visit(std::type_identity<msg::ImuBatch>{});
  visit(std::type_identity<msg::ImuCalibration>{});
  visit(std::type_identity<msg::Odometry>{});
  visit(std::type_identity<msg::Keyframe>{});
  visit(std::type_identity<msg::KeyframeState>{});
  visit(std::type_identity<msg::MapPointState>{});
  visit(std::type_identity<msg::LoopCorrection>{});
  visit(std::type_identity<msg::FrameDone>{});
  visit(std::type_identity<msg::KeyframeDone>{});
  visit(std::type_identity<msg::ComponentStatus>{});
  visit(std::type_identity<msg::OccupancyGrid2D>{});
  visit(std::type_identity<msg::DenseCloud>{});
  visit(std::type_identity<msg::OccupancySaveRequest>{});
  visit(std::type_identity<msg::OccupancySaveReply>{});
  if (!found) throw std::runtime_error("type '" + std::string(type_name) + "': not compiled into heslam-spy");
}

}  // namespace heslam
