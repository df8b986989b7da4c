// The QoS profile of each role (figures and reasons: shared/notes/cyclonedds-0.10-findings.md).
#include "runtime/qos.hpp"

#include <string_view>
#include <utility>

#include "runtime/run_id.hpp"

namespace heslam::runtime {
namespace {

using std::chrono::milliseconds;

// Images: a writer facing a slow reader blocks at most this long before KEEP_LAST overwrites.
constexpr milliseconds kImageMaxBlocking{100};
// Frames kept per reader: enough to absorb a hiccup, few enough that a slow frontend sees fresh data.
constexpr int32_t kImageDepth = 4;
// Odometry kept per reader, and replayed to a late (restarted, or stalled past the 2 s lease and
// rematched) reader: 60 s at 20 Hz, so a recorder loses no pose to a stall or a restart that short.
// With 100, a recorder stopped 5 s while 400 frames were published wrote 220 of 420
// (RecorderProcess test). ~800 B a sample: ~1 MB of writer history, well under the 8 MB WhcHigh of
// config/cyclonedds.xml, so the frontend's writes are never throttled.
constexpr int32_t kOdometryDepth = 1200;
// Corrections are rare and precious; KEEP_ALL with a short block, replay the last 100 to late joiners
// (replay depth comes from durability_service, not history: findings pitfall 7).
constexpr milliseconds kCorrectionMaxBlocking{100};
constexpr int32_t kCorrectionReplayDepth = 100;
// Lockstep acks: tiny, one per frame; 64 covers any realistic backlog without KEEP_ALL blocking.
constexpr int32_t kLockstepDepth = 64;
// IMU batches: one per frame from the replay (10 readings at 200 Hz / 20 Hz), more from a driver that
// publishes every reading (heslam-ros2-input: one per reading it takes). 2048 batches is 10 s of a 200 Hz
// driver, so a frontend starved of CPU for seconds still gets every reading (256 lost readings to a frontend
// held 1.3 s); about 100 B a batch of one reading, 200 KB of history.
constexpr int32_t kImuDepth = 2048;
// Default blocking for other reliable writers (KEEP_LAST never blocks long; bounds pathological cases).
constexpr milliseconds kDefaultMaxBlocking{100};
// Status is published every second; the supervisor declares a writer gone after 2 missed periods.
constexpr milliseconds kStatusLiveliness{2000};

void apply(dds_qos_t* qos, QosRole role) {
  switch (role) {
    case QosRole::kImages:
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kImageMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, kImageDepth);
      break;
    case QosRole::kCalibration:
    case QosRole::kKeyframes:
    case QosRole::kMapState:
      // Keyed (or single-instance) state: KEEP_LAST(1) per instance never blocks and is all a late
      // joiner needs; durability_service depth must match for the replay (pitfall 7).
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kDefaultMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
      dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, 1, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED);
      break;
    case QosRole::kOdometry:
      // Transient-local: a recorder restarted mid-run gets the frames published while it was down
      // (its journal holds the earlier ones); durability_service depth must match (pitfall 7).
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kDefaultMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, kOdometryDepth);
      dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, kOdometryDepth, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
      break;
    case QosRole::kCorrections:
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kCorrectionMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
      dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, kCorrectionReplayDepth, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
      break;
    case QosRole::kLockstep:
      // Transient-local: discovery matches each direction on its own, so a consumer can take its first
      // frame before its ack writer has matched the publisher's ack reader; a volatile ack written
      // then is lost and the lockstep run stalls. The reader gets the recent acks when it matches
      // (durability_service depth must match, pitfall 7); acks are per seq, so a replayed one is harmless.
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kDefaultMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, kLockstepDepth);
      dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, kLockstepDepth, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
      break;
    case QosRole::kImu:
      // Transient-local for the reason of kLockstep: a frontend whose IMU reader matches after the
      // replay's first batch (discovery matches each topic on its own) still receives it. KEEP_LAST
      // never blocks the source; a reader that falls kImuDepth batches behind sees the gap in first_index.
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kDefaultMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, kImuDepth);
      dds_qset_durability_service(qos, 0, DDS_HISTORY_KEEP_LAST, kImuDepth, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                                  DDS_LENGTH_UNLIMITED);
      break;
    case QosRole::kStatus:
      // Reliable: a component's last sample before it exits carries its result (the recorder's
      // "tracked N/M frames ...") that the supervisor's last line reports; KEEP_LAST(1) never blocks.
      dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(kDefaultMaxBlocking.count()));
      dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
      dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC, DDS_MSECS(kStatusLiveliness.count()));
      break;
    case QosRole::kSpy:
      dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
      dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
      dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
      break;
  }
}

}  // namespace

std::string_view to_string(QosRole role) {
  switch (role) {
    case QosRole::kImages: return "images";
    case QosRole::kCalibration: return "calibration";
    case QosRole::kOdometry: return "odometry";
    case QosRole::kKeyframes: return "keyframes";
    case QosRole::kMapState: return "map-state";
    case QosRole::kCorrections: return "corrections";
    case QosRole::kImu: return "imu";
    case QosRole::kLockstep: return "lockstep";
    case QosRole::kStatus: return "status";
    case QosRole::kSpy: return "spy";
  }
  return "unknown";
}

Qos::Qos(QosRole role) : role_(role), qos_(dds_create_qos()) { apply(qos_, role); }

Qos::~Qos() {
  if (qos_ != nullptr) dds_delete_qos(qos_);
}

Qos::Qos(const Qos& other) : role_(other.role_), qos_(dds_create_qos()) { dds_copy_qos(qos_, other.qos_); }

Qos& Qos::operator=(const Qos& other) {
  if (this != &other) {
    role_ = other.role_;
    dds_copy_qos(qos_, other.qos_);
  }
  return *this;
}

Qos::Qos(Qos&& other) noexcept : role_(other.role_), qos_(std::exchange(other.qos_, nullptr)) {}

Qos& Qos::operator=(Qos&& other) noexcept {
  if (this != &other) {
    if (qos_ != nullptr) dds_delete_qos(qos_);
    role_ = other.role_;
    qos_ = std::exchange(other.qos_, nullptr);
  }
  return *this;
}

Qos& Qos::keep_last(int32_t depth) {
  dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, depth);
  return *this;
}

Qos& Qos::keep_all() {
  dds_qset_history(qos_, DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
  return *this;
}

Qos& Qos::reliable(std::chrono::milliseconds max_blocking_time) {
  dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, DDS_MSECS(max_blocking_time.count()));
  return *this;
}

Qos& Qos::best_effort() {
  dds_qset_reliability(qos_, DDS_RELIABILITY_BEST_EFFORT, 0);
  return *this;
}

Qos& Qos::volatile_durability() {
  dds_qset_durability(qos_, DDS_DURABILITY_VOLATILE);
  return *this;
}

Qos& Qos::transient_local(int32_t replay_depth) {
  dds_qset_durability(qos_, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_durability_service(qos_, 0, DDS_HISTORY_KEEP_LAST, replay_depth, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                              DDS_LENGTH_UNLIMITED);
  return *this;
}

Qos& Qos::keep_instances_on_writer_exit() {
  dds_qset_writer_data_lifecycle(qos_, false);
  return *this;
}

Qos& Qos::run_identity(const std::string& run_id) {
  const std::string user_data = std::string(kRunUserDataPrefix) + run_id;
  dds_qset_userdata(qos_, user_data.data(), user_data.size());
  return *this;
}

bool Qos::has_run_identity() const {
  void* value = nullptr;
  size_t size = 0;
  if (!dds_qget_userdata(qos_, &value, &size) || value == nullptr) return false;
  const bool is_run = std::string_view(static_cast<const char*>(value), size).starts_with(kRunUserDataPrefix);
  dds_free(value);
  return is_run;
}

}  // namespace heslam::runtime
