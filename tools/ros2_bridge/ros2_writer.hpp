// Ros2Writer<T>: a writer of one ROS 2 type (ros2_messages.hpp) on one DDS topic, over the C API.
#pragma once

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "runtime/entity.hpp"
#include "runtime/participant.hpp"
#include "runtime/qos.hpp"
#include "tools/ros2_bridge/ros2_messages.hpp"

namespace heslam::ros2 {

// A writer of one ROS 2 type on one DDS topic; throws std::runtime_error naming the topic.
template <typename T>
class Ros2Writer {
 public:
  Ros2Writer(const runtime::Participant& participant, const dds_topic_descriptor_t* descriptor, std::string topic,
             const runtime::Qos& qos)
      : name_(std::move(topic)) {
    topic_ = runtime::Entity(
        runtime::check_dds(dds_create_topic(participant.handle(), descriptor, name_.c_str(), nullptr, nullptr),
                           "topic '" + name_ + "': cannot create topic"));
    writer_ =
        runtime::Entity(runtime::check_dds(dds_create_writer(participant.handle(), topic_.get(), qos.get(), nullptr),
                                           "topic '" + name_ + "': cannot create writer"));
  }

  void write(const T& sample) {
    const dds_return_t result = dds_write(writer_.get(), &sample);
    // A reliable reader that keeps up never makes this time out; a dead one costs one sample.
    if (result < 0 && result != DDS_RETCODE_TIMEOUT) {
      throw std::runtime_error("topic '" + name_ + "': write failed: " + dds_strretcode(result));
    }
  }

  // True once a reader matched, false after `timeout` without one.
  bool wait_for_readers(std::chrono::duration<double> timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      dds_publication_matched_status_t status{};
      if (dds_get_publication_matched_status(writer_.get(), &status) == DDS_RETCODE_OK && status.current_count > 0) {
        return true;
      }
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  const std::string& name() const { return name_; }

 private:
  std::string name_;
  runtime::Entity topic_;
  runtime::Entity writer_;
};

}  // namespace heslam::ros2
