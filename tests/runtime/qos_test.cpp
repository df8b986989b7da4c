// QoS profiles: each role carries the settings the findings require, read back from the dds_qos_t.
#include "runtime/qos.hpp"

#include <gtest/gtest.h>

namespace heslam::runtime {
namespace {

struct Read {
  dds_reliability_kind_t reliability{};
  dds_duration_t max_blocking{};
  dds_durability_kind_t durability{};
  dds_history_kind_t history{};
  int32_t depth = 0;
};

Read read(const Qos& qos) {
  Read r;
  EXPECT_TRUE(dds_qget_reliability(qos.get(), &r.reliability, &r.max_blocking));
  EXPECT_TRUE(dds_qget_durability(qos.get(), &r.durability));
  EXPECT_TRUE(dds_qget_history(qos.get(), &r.history, &r.depth));
  return r;
}

int32_t replay_depth(const Qos& qos) {
  dds_duration_t cleanup = 0;
  dds_history_kind_t kind{};
  int32_t depth = 0, samples = 0, instances = 0, per_instance = 0;
  EXPECT_TRUE(dds_qget_durability_service(qos.get(), &cleanup, &kind, &depth, &samples, &instances, &per_instance));
  EXPECT_EQ(kind, DDS_HISTORY_KEEP_LAST);
  return depth;
}

TEST(Qos, ImagesAreVolatileKeepLastWithShortBlocking) {
  const Read r = read(Qos(QosRole::kImages));
  EXPECT_EQ(r.reliability, DDS_RELIABILITY_RELIABLE);
  EXPECT_EQ(r.max_blocking, DDS_MSECS(100));
  EXPECT_EQ(r.durability, DDS_DURABILITY_VOLATILE);
  EXPECT_EQ(r.history, DDS_HISTORY_KEEP_LAST);
  EXPECT_EQ(r.depth, 4);
}

TEST(Qos, StateRolesAreTransientLocalKeepLastOneWithMatchingReplayDepth) {
  for (QosRole role : {QosRole::kCalibration, QosRole::kKeyframes, QosRole::kMapState}) {
    const Qos qos(role);
    const Read r = read(qos);
    EXPECT_EQ(r.reliability, DDS_RELIABILITY_RELIABLE) << to_string(role);
    EXPECT_EQ(r.durability, DDS_DURABILITY_TRANSIENT_LOCAL) << to_string(role);
    EXPECT_EQ(r.history, DDS_HISTORY_KEEP_LAST) << to_string(role);
    EXPECT_EQ(r.depth, 1) << to_string(role);
    EXPECT_EQ(replay_depth(qos), 1) << to_string(role);
  }
}

TEST(Qos, CorrectionsKeepAllAndReplayAHundred) {
  const Qos qos(QosRole::kCorrections);
  const Read r = read(qos);
  EXPECT_EQ(r.history, DDS_HISTORY_KEEP_ALL);
  EXPECT_EQ(r.durability, DDS_DURABILITY_TRANSIENT_LOCAL);
  EXPECT_EQ(r.max_blocking, DDS_MSECS(100));
  EXPECT_EQ(replay_depth(qos), 100);
}

TEST(Qos, LockstepAcksAreTransientLocalWithMatchingReplayDepth) {
  const Qos qos(QosRole::kLockstep);
  const Read r = read(qos);
  EXPECT_EQ(r.reliability, DDS_RELIABILITY_RELIABLE);
  EXPECT_EQ(r.durability, DDS_DURABILITY_TRANSIENT_LOCAL);
  EXPECT_EQ(r.history, DDS_HISTORY_KEEP_LAST);
  EXPECT_EQ(r.depth, 64);
  EXPECT_EQ(replay_depth(qos), 64);
}

TEST(Qos, StatusIsReliableAndSpyBestEffortBothKeepLastOne) {
  EXPECT_EQ(read(Qos(QosRole::kStatus)).reliability, DDS_RELIABILITY_RELIABLE);  // the last sample carries the result
  EXPECT_EQ(read(Qos(QosRole::kSpy)).reliability, DDS_RELIABILITY_BEST_EFFORT);
  for (QosRole role : {QosRole::kStatus, QosRole::kSpy}) {
    const Read r = read(Qos(role));
    EXPECT_EQ(r.durability, DDS_DURABILITY_VOLATILE) << to_string(role);
    EXPECT_EQ(r.depth, 1) << to_string(role);
  }
  dds_liveliness_kind_t kind{};
  dds_duration_t lease = 0;
  ASSERT_TRUE(dds_qget_liveliness(Qos(QosRole::kStatus).get(), &kind, &lease));
  EXPECT_EQ(kind, DDS_LIVELINESS_AUTOMATIC);
  EXPECT_EQ(lease, DDS_SECS(2));
}

TEST(Qos, OverridesAndCopiesAreIndependent) {
  Qos base(QosRole::kOdometry);
  Qos copy = base;
  copy.keep_all().best_effort();
  EXPECT_EQ(read(base).history, DDS_HISTORY_KEEP_LAST);
  EXPECT_EQ(read(base).depth, 1200);
  EXPECT_EQ(read(copy).history, DDS_HISTORY_KEEP_ALL);
  EXPECT_EQ(read(copy).reliability, DDS_RELIABILITY_BEST_EFFORT);
  Qos moved = std::move(copy);
  EXPECT_EQ(read(moved).history, DDS_HISTORY_KEEP_ALL);
}

}  // namespace
}  // namespace heslam::runtime
