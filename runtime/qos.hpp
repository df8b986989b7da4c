// QoS profiles by role. Every topic's QoS comes from here (via runtime/topics.hpp), with the fixes
// measured in shared/notes/cyclonedds-0.10-findings.md; see docs/topics.md for the table.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

#include <dds/dds.h>

namespace heslam::runtime {

enum class QosRole {
  kImages,       // reliable, volatile, KEEP_LAST(4), 100 ms max blocking: a slow reader drops frames
  kCalibration,  // reliable, transient-local, KEEP_LAST(1): late joiners get the current calibration
  kOdometry,     // reliable, transient-local, KEEP_LAST(1200): a stalled recorder catches up; never blocks
  kKeyframes,    // keyed, reliable, transient-local, KEEP_LAST(1) per instance (one version per id)
  kMapState,     // keyed, reliable, transient-local, KEEP_LAST(1) per instance; deletions are disposes
  kCorrections,  // reliable, transient-local, KEEP_ALL + durability_service KEEP_LAST(100), 100 ms blocking
  kImu,          // reliable, transient-local, KEEP_LAST(2048): IMU batches, none lost to a reader matched late
  kLockstep,     // reliable, volatile, KEEP_LAST(64): acknowledgements are tiny and must not be lost
  kStatus,       // keyed by name, reliable, volatile, KEEP_LAST(1), liveliness automatic 2 s
  kSpy,          // readers only: best effort, KEEP_LAST(1), volatile — tapping never slows writers
};

std::string_view to_string(QosRole role);

// An owned dds_qos_t. Start from a role's profile and adjust with the setters if a reader or writer
// really needs something else (say why next to the call).
class Qos {
 public:
  explicit Qos(QosRole role);
  ~Qos();
  Qos(const Qos& other);
  Qos& operator=(const Qos& other);
  Qos(Qos&& other) noexcept;
  Qos& operator=(Qos&& other) noexcept;

  Qos& keep_last(int32_t depth);
  Qos& keep_all();
  Qos& reliable(std::chrono::milliseconds max_blocking_time);
  Qos& best_effort();
  Qos& volatile_durability();
  Qos& transient_local(int32_t replay_depth);  // also sets durability_service KEEP_LAST(replay_depth)
  // Writers only: deleting the writer (process exit) unregisters its instances WITHOUT disposing
  // them, so readers keep the state (DDS default: dispose, i.e. "deleted").
  Qos& keep_instances_on_writer_exit();
  // Writers only: the run the writer belongs to, as its user data (kRunUserDataPrefix + run_id;
  // runtime/run_id.hpp). Writer<T> sets process_run_id() unless the QoS has a run already.
  Qos& run_identity(const std::string& run_id);
  bool has_run_identity() const;

  const dds_qos_t* get() const { return qos_; }
  QosRole role() const { return role_; }

 private:
  QosRole role_;
  dds_qos_t* qos_;
};

}  // namespace heslam::runtime
