// Topic<T>: a typed DDS topic of one participant, created from a TopicSpec of runtime/topics.hpp.
#pragma once

#include <string>

#include "runtime/entity.hpp"
#include "runtime/messages.hpp"
#include "runtime/participant.hpp"
#include "runtime/topics.hpp"

namespace heslam::runtime {

template <Message T>
class Topic {
 public:
  // Throws std::runtime_error naming the topic when DDS refuses (e.g. same name, different type).
  Topic(const Participant& participant, const TopicSpec<T>& spec)
      : spec_(spec),
        entity_(check_dds(
            dds_create_topic(participant.handle(), MessageTraits<T>::descriptor(), spec.name.c_str(), nullptr, nullptr),
            "topic '" + spec.name + "': cannot create")) {}

  dds_entity_t handle() const { return entity_.get(); }
  const TopicSpec<T>& spec() const { return spec_; }
  const std::string& name() const { return spec_.name; }

 private:
  TopicSpec<T> spec_;
  Entity entity_;
};

}  // namespace heslam::runtime
