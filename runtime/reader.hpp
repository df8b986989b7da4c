// Reader<T>: a typed data reader that takes samples into owned Sample<T> objects.
//
// Samples from a build with a different message schema are dropped, counted and reported once
// (stderr), so mismatched builds fail loudly instead of misreading bytes.
#pragma once

#include <chrono>
#include <cstdint>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "runtime/entity.hpp"
#include "runtime/qos.hpp"
#include "runtime/sample.hpp"
#include "runtime/topic.hpp"

namespace heslam::runtime {

// One line naming the topic and both versions (also used by the supervisor's status check).
std::string schema_mismatch_message(const std::string& topic, uint32_t received_version);

template <Message T>
class Reader {
 public:
  // qos: override of the role's profile, e.g. Qos(QosRole::kSpy) for a tap.
  Reader(const Participant& participant, const TopicSpec<T>& spec, std::optional<Qos> qos = std::nullopt)
      : topic_(participant, spec) {
    const Qos effective = qos ? *qos : Qos(spec.role);
    entity_ = Entity(check_dds(dds_create_reader(participant.handle(), topic_.handle(), effective.get(), nullptr),
                               "topic '" + spec.name + "': cannot create reader"));
  }

  // Takes up to max_samples (oldest first). Includes invalid-data samples (dispose / no-writer
  // notices: only key fields are set; check info.valid_data).
  std::vector<Received<T>> take(std::size_t max_samples = kDefaultBatch) {
    std::vector<Received<T>> out;
    while (out.size() < max_samples) {
      std::optional<Received<T>> one = take_one();
      if (!one) break;
      out.push_back(std::move(*one));
    }
    return out;
  }

  // Takes the oldest sample, or nothing when the reader is empty.
  std::optional<Received<T>> take_one() {
    Received<T> received;
    if (!take_into(received)) return std::nullopt;
    return received;
  }

  // Takes the oldest sample into `received`, reusing its buffers: Cyclone deserializes into the
  // sequences and strings already there, growing them only when too small, so a stream of 722 KB
  // stereo pairs allocates nothing per frame. Returns false when the reader is empty (`received`
  // then holds nothing new to use). On an invalid-data sample only the key fields are current; the others keep
  // the previous sample's values (check info.valid_data). `received` must not be a moved-from object.
  bool take_into(Received<T>& received) {
    for (;;) {
      void* buffer = received.sample.get();
      dds_sample_info_t info{};
      const dds_return_t n = dds_take(entity_.get(), &buffer, &info, 1, 1);
      check_dds(n, "topic '" + name() + "': take failed");
      if (n == 0) return false;
      received.info.valid_data = info.valid_data;
      received.info.disposed = info.instance_state == DDS_IST_NOT_ALIVE_DISPOSED;
      received.info.no_writers = info.instance_state == DDS_IST_NOT_ALIVE_NO_WRITERS;
      received.info.source_stamp_ns = info.source_timestamp;
      received.info.publication_handle = info.publication_handle;
      received.info.instance_handle = info.instance_handle;
      if (info.valid_data && received.sample->schema_version != msg::kSchemaVersion) {
        if (schema_mismatches_++ == 0)
          std::cerr << schema_mismatch_message(name(), received.sample->schema_version) << "\n";
        continue;
      }
      return true;
    }
  }

  // Whether a sample is waiting that has not been taken (non-destructive: nothing is read or taken).
  // For work that should yield to new input, e.g. a real-time bundle adjustment.
  bool has_unread() {
    if (!unread_condition_) {
      unread_condition_ =
          Entity(check_dds(dds_create_readcondition(
                               entity_.get(), DDS_NOT_READ_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ANY_INSTANCE_STATE),
                           "topic '" + name() + "': cannot create read condition"));
    }
    return check_dds(dds_triggered(unread_condition_.get()), "topic '" + name() + "': read condition") > 0;
  }

  // Writers currently matched.
  int matched_writers() const {
    dds_subscription_matched_status_t status{};
    check_dds(dds_get_subscription_matched_status(entity_.get(), &status), "topic '" + name() + "': matched status");
    return static_cast<int>(status.current_count);
  }

  bool wait_for_writers(int count, std::chrono::milliseconds timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (matched_writers() < count) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(kMatchPollPeriod);
    }
    return true;
  }

  // Samples dropped because their schema_version differs from this build's.
  uint64_t schema_mismatches() const { return schema_mismatches_; }

  const std::string& name() const { return topic_.name(); }
  dds_entity_t handle() const { return entity_.get(); }

 private:
  static constexpr std::size_t kDefaultBatch = 64;
  static constexpr std::chrono::milliseconds kMatchPollPeriod{5};

  Topic<T> topic_;
  Entity entity_;
  Entity unread_condition_;  // created by the first has_unread(); a child of entity_
  uint64_t schema_mismatches_ = 0;
};

}  // namespace heslam::runtime
