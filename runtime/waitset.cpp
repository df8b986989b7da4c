// WaitSet over dds_waitset_wait: read conditions for readers, a wake guard, and a shutdown guard.
#include "runtime/waitset.hpp"

#include "runtime/shutdown.hpp"
#include "runtime/shutdown_registry.hpp"

namespace heslam::runtime {
namespace {

// Attachment arguments of the two guards (reader tokens are 0, 1, 2, ...).
constexpr dds_attach_t kWakeToken = -1;
constexpr dds_attach_t kShutdownToken = -2;

}  // namespace

WaitSet::WaitSet(const Participant& participant, WaitScope scope) : participant_(participant.handle()) {
  // Cyclone lets a waitset attach only entities under its owner; the library root owns every domain.
  const dds_entity_t owner = scope == WaitScope::kAllDomains ? DDS_CYCLONEDDS_HANDLE : participant_;
  waitset_ = Entity(check_dds(dds_create_waitset(owner), "waitset: cannot create"));
  wake_guard_ = Entity(check_dds(dds_create_guardcondition(participant_), "waitset: cannot create guard"));
  shutdown_guard_ = Entity(check_dds(dds_create_guardcondition(participant_), "waitset: cannot create guard"));
  check_dds(dds_waitset_attach(waitset_.get(), wake_guard_.get(), kWakeToken), "waitset: attach");
  check_dds(dds_waitset_attach(waitset_.get(), shutdown_guard_.get(), kShutdownToken), "waitset: attach");
  detail::register_shutdown_guard(shutdown_guard_.get());
}

WaitSet::~WaitSet() { detail::unregister_shutdown_guard(shutdown_guard_.get()); }

int WaitSet::attach(dds_entity_t reader) {
  const int token = static_cast<int>(conditions_.size());
  Entity condition(check_dds(dds_create_readcondition(reader, DDS_ANY_STATE), "waitset: cannot create read condition"));
  check_dds(dds_waitset_attach(waitset_.get(), condition.get(), token), "waitset: attach reader");
  conditions_.push_back(std::move(condition));
  return token;
}

Wake WaitSet::wait(std::chrono::nanoseconds timeout) {
  ready_.clear();
  if (shutdown_requested()) return Wake::kShutdown;
  std::vector<dds_attach_t> triggered(conditions_.size() + 2);
  const dds_return_t n = dds_waitset_wait(waitset_.get(), triggered.data(), triggered.size(), timeout.count());
  check_dds(n, "waitset: wait failed");
  if (shutdown_requested()) return Wake::kShutdown;
  bool woken = false;
  for (dds_return_t i = 0; i < n; ++i) {
    const dds_attach_t token = triggered[static_cast<std::size_t>(i)];
    if (token == kWakeToken) woken = true;
    if (token >= 0) ready_.push_back(static_cast<int>(token));
  }
  // Data first; a pending wake stays set and is reported by the next wait().
  if (!ready_.empty()) return Wake::kData;
  if (woken) {
    bool was_set = false;
    dds_take_guardcondition(wake_guard_.get(), &was_set);
    return Wake::kWoken;
  }
  return Wake::kTimeout;
}

void WaitSet::wake() { dds_set_guardcondition(wake_guard_.get(), true); }

}  // namespace heslam::runtime
