// Ros2Reader<T>: a reader of one ROS 2 type (ros2_messages.hpp) on one DDS topic, over the C API.
#pragma once

#include <string>

#include "runtime/entity.hpp"
#include "runtime/participant.hpp"
#include "runtime/qos.hpp"
#include "tools/ros2_bridge/ros2_messages.hpp"

namespace heslam::ros2 {

// Throws std::runtime_error naming the topic when the topic or reader cannot be created.
template <typename T>
class Ros2Reader {
 public:
  Ros2Reader(const runtime::Participant& participant, const dds_topic_descriptor_t* descriptor, std::string topic,
             const runtime::Qos& qos)
      : descriptor_(descriptor), name_(std::move(topic)) {
    topic_ = runtime::Entity(
        runtime::check_dds(dds_create_topic(participant.handle(), descriptor, name_.c_str(), nullptr, nullptr),
                           "topic '" + name_ + "': cannot create topic"));
    reader_ =
        runtime::Entity(runtime::check_dds(dds_create_reader(participant.handle(), topic_.get(), qos.get(), nullptr),
                                           "topic '" + name_ + "': cannot create reader"));
  }

  // Hands every sample waiting (valid data only) to use(const T&), which sees it while it is alive.
  template <typename Use>
  int take_all(Use use) {
    int taken = 0;
    for (;;) {
      void* sample = dds_alloc(descriptor_->m_size);
      dds_sample_info_t info{};
      void* buffer[1] = {sample};
      const dds_return_t n = dds_take(reader_.get(), buffer, &info, 1, 1);
      if (n > 0 && info.valid_data) {
        use(*static_cast<const T*>(sample));
        ++taken;
      }
      dds_sample_free(sample, descriptor_, DDS_FREE_ALL);
      if (n <= 0) return taken;
    }
  }

  const std::string& name() const { return name_; }

 private:
  const dds_topic_descriptor_t* descriptor_;
  std::string name_;
  runtime::Entity topic_;
  runtime::Entity reader_;
};

}  // namespace heslam::ros2
