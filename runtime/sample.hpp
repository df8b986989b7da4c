// Sample<T>: one message owned by C++ — the C struct plus every buffer Cyclone malloc'ed into it
// during a take — freed exactly once (dds_sample_free) when the Sample is destroyed.
#pragma once

#include <memory>
#include <utility>

#include "runtime/messages.hpp"

namespace heslam::runtime {

template <Message T>
class Sample {
 public:
  // A zeroed sample: empty sequences, null strings. Takes fill it; destruction frees what they filled.
  Sample() : data_(static_cast<T*>(dds_alloc(sizeof(T)))) {}

  Sample(Sample&&) noexcept = default;
  Sample& operator=(Sample&&) noexcept = default;
  Sample(const Sample&) = delete;
  Sample& operator=(const Sample&) = delete;

  T& operator*() { return *data_; }
  const T& operator*() const { return *data_; }
  T* operator->() { return data_.get(); }
  const T* operator->() const { return data_.get(); }
  T* get() { return data_.get(); }
  const T* get() const { return data_.get(); }

 private:
  struct Free {
    void operator()(T* sample) const { dds_sample_free(sample, MessageTraits<T>::descriptor(), DDS_FREE_ALL); }
  };
  std::unique_ptr<T, Free> data_;
};

// What DDS says about a taken sample besides its data.
struct SampleInfo {
  bool valid_data = false;                       // false: only the key fields are set (a dispose / unregister notice)
  bool disposed = false;                         // the instance was disposed (a deleted keyframe / point)
  bool no_writers = false;                       // the instance's writers are gone (writer died or unregistered)
  std::int64_t source_stamp_ns = 0;              // the writer's write time (CLOCK_REALTIME)
  dds_instance_handle_t publication_handle = 0;  // which writer sent it
  dds_instance_handle_t instance_handle = 0;     // which instance (key value) of a keyed topic
};

template <Message T>
struct Received {
  Sample<T> sample;
  SampleInfo info;
};

}  // namespace heslam::runtime
