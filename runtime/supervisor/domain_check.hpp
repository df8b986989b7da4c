// Other heslam runs on the supervisor's DDS domain: the writers of the run's namespace that belong to
// neither this supervisor nor its children (their user data names another run, runtime/run_id.hpp),
// seen on the built-in publication topic. Checked before anything starts (another run alive there:
// refuse, or --domain auto picks a free domain) and watched during the run (its verdict says so).
#pragma once

#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <dds/dds.h>

#include "runtime/supervisor/pipeline.hpp"

namespace heslam::supervisor {

class OtherRunWatch {
 public:
  // Watches the domain of `participant` for writers of topics "<ns>/..." of other runs than
  // `own_run` (what this supervisor's children advertise) and not of `participant` itself.
  OtherRunWatch(dds_entity_t participant, std::string ns, std::string own_run);
  ~OtherRunWatch();
  OtherRunWatch(const OtherRunWatch&) = delete;
  OtherRunWatch& operator=(const OtherRunWatch&) = delete;

  // Takes the publications discovered since the last call; returns true when a writer of another
  // run was among them.
  bool poll();
  // The other runs seen so far, e.g. "run 4242:1934 (writers of heslam/odometry, heslam/system/status)".
  std::string describe() const;
  bool seen() const { return !runs_.empty(); }
  // Forgets what was seen (the domain was checked): poll() reports only writers that appear later.
  void forget() { runs_.clear(); }
  // Writers of other runs that are still alive (a killed run's stay until their lease expires).
  std::size_t alive() const { return alive_.size(); }
  // Whether every run seen is of a process on this host that is gone: a run that was killed, whose
  // writers only wait for their DDS lease to expire.
  bool all_runs_ended_here() const;

 private:
  dds_entity_t reader_ = 0;
  dds_guid_t own_participant_{};
  std::string prefix_;
  std::string own_run_;
  std::map<std::string, std::set<std::string>> runs_;  // run id -> topics
  std::set<std::vector<unsigned char>> alive_;         // their writers' GUIDs, while alive
};

// A claim of this host's supervisors on a (domain, namespace): an exclusive lock on a file under
// $TMPDIR/heslam-domains, held for the supervisor's life and released by the kernel when it dies. It
// settles at once, without DDS, which of two runs started together on one host gets the domain.
class DomainClaim {
 public:
  // The claim, or nothing when another process holds it (its pid in `holder`, when it wrote one).
  static std::optional<DomainClaim> try_claim(int domain_id, const std::string& ns, std::string* holder = nullptr);
  DomainClaim(DomainClaim&& other) noexcept;
  DomainClaim& operator=(DomainClaim&& other) noexcept;
  DomainClaim(const DomainClaim&) = delete;
  DomainClaim& operator=(const DomainClaim&) = delete;
  ~DomainClaim();

 private:
  explicit DomainClaim(int fd) : fd_(fd) {}
  int fd_ = -1;
};

// Listens up to `window` (until a writer of another run is seen, then while only writers of ended
// local runs are seen, up to `stale_window`) and describes the other run alive on the domain, if any.
std::optional<std::string> other_run_alive(OtherRunWatch& watch, std::chrono::milliseconds window,
                                           std::chrono::milliseconds stale_window);

// With heslam's built-in Cyclone configuration (config/cyclonedds.xml: loopback only, no multicast,
// participant index auto) only this host's processes can be on a domain, and each DDS participant
// there binds its index's unicast discovery port. Whether a socket of another process binds one of
// the domain's discovery ports (/proc/net/udp and udp6, this process's own sockets left out): false
// means no other participant can hear or be heard on the domain. Nothing when that cannot be told
// (another configuration: `dds_config` set, given by $CYCLONEDDS_URI, or /proc unreadable).
std::optional<bool> other_participant_on_host(const Pipeline& pipeline, int domain_id);

// --domain auto: the first domain (the pipeline's, then 1, 2, ..., 232, 0) that this host's
// supervisors have not claimed and on which no other run's writer is heard within a second; its
// claim is left in `claim`. Throws when every domain is in use.
int free_domain(const Pipeline& pipeline, std::optional<DomainClaim>& claim);

}  // namespace heslam::supervisor
