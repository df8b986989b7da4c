// Writer<T>: a typed data writer with the QoS of its topic's role.
//
// write() stamps schema_version into a shallow copy of the sample (so callers never set it), then
// serialises immediately: buffers borrowed with runtime::borrow() may be reused as soon as it returns.
#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "runtime/entity.hpp"
#include "runtime/qos.hpp"
#include "runtime/run_id.hpp"
#include "runtime/topic.hpp"

namespace heslam::runtime {

enum class WriteResult {
  kOk,
  kTimeout,  // a reliable KEEP_ALL writer stayed blocked max_blocking_time (reader dead or too slow)
};

template <Message T>
class Writer {
 public:
  // qos: override of the role's profile (rarely needed).
  Writer(const Participant& participant, const TopicSpec<T>& spec, std::optional<Qos> qos = std::nullopt)
      : topic_(participant, spec) {
    Qos effective = qos ? *qos : Qos(spec.role);
    // Who may succeed this writer on a single-writer topic: a writer of the same run (a restart).
    if (!effective.has_run_identity()) effective.run_identity(process_run_id());
    entity_ = Entity(check_dds(dds_create_writer(participant.handle(), topic_.handle(), effective.get(), nullptr),
                               "topic '" + spec.name + "': cannot create writer"));
  }

  // Throws std::runtime_error("topic 'X': write failed: <reason>") on errors other than a timeout.
  WriteResult write(const T& sample) { return call(dds_write, sample, "write"); }
  // Deletes the instance with sample's key (map state: a culled keyframe / point).
  WriteResult dispose(const T& key_sample) { return call(dds_dispose, key_sample, "dispose"); }
  // Drops this writer's interest in the instance (readers see no_writers when none is left).
  WriteResult unregister(const T& key_sample) { return call(dds_unregister_instance, key_sample, "unregister"); }

  // Readers currently matched (discovery is asynchronous: volatile data written before a reader
  // matched is lost to it).
  int matched_readers() const {
    dds_publication_matched_status_t status{};
    check_dds(dds_get_publication_matched_status(entity_.get(), &status), "topic '" + name() + "': matched status");
    return static_cast<int>(status.current_count);
  }

  // Instance handles of the readers currently matched: a handle not seen before is a reader that
  // (re)appeared, e.g. a restarted consumer.
  std::vector<dds_instance_handle_t> matched_reader_handles() const {
    std::vector<dds_instance_handle_t> handles(16);
    for (;;) {
      const dds_return_t n = check_dds(dds_get_matched_subscriptions(entity_.get(), handles.data(), handles.size()),
                                       "topic '" + name() + "': matched subscriptions");
      if (static_cast<std::size_t>(n) <= handles.size()) {
        handles.resize(static_cast<std::size_t>(n));
        return handles;
      }
      handles.resize(static_cast<std::size_t>(n));  // more matched than room: ask again with enough
    }
  }

  // Polls until at least count readers matched; false on timeout.
  bool wait_for_readers(int count, std::chrono::milliseconds timeout) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (matched_readers() < count) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      std::this_thread::sleep_for(kMatchPollPeriod);
    }
    return true;
  }

  const std::string& name() const { return topic_.name(); }
  dds_entity_t handle() const { return entity_.get(); }

 private:
  // Discovery on loopback takes tens of ms; 5 ms polling adds little latency and no load.
  static constexpr std::chrono::milliseconds kMatchPollPeriod{5};

  template <typename Fn>
  WriteResult call(Fn fn, const T& sample, const char* what) {
    T stamped = sample;  // shallow: sequences still point at the caller's buffers
    stamped.schema_version = msg::kSchemaVersion;
    const dds_return_t ret = fn(entity_.get(), &stamped);
    if (ret == DDS_RETCODE_TIMEOUT) return WriteResult::kTimeout;
    check_dds(ret, "topic '" + name() + "': " + what + " failed");
    return WriteResult::kOk;
  }

  Topic<T> topic_;
  Entity entity_;
};

}  // namespace heslam::runtime
