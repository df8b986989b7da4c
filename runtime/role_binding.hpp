// RoleBinding: who may speak for a role on a topic several components write (lockstep/frame_done,
// lockstep/keyframe_done). Plain DDS cannot tell a forged participant from a real
// one (a forger can copy the run id), but it can notice two live writers claiming one role:
//
// - The first writer whose sample claims a role is bound to it; its samples are accepted.
// - A sample of another writer for the role while the bound one is still matched is held back (the
//   caller keeps it and asks again): a restarted component's first acknowledgement arrives while the
//   killed one still counts as matched (its 2 s lease). Once the bound writer is gone, the claimant
//   takes the role over and its held samples are accepted.
// - If the bound writer writes again while a claimant is still matched, both are alive: a conflict;
//   so is a claimant acknowledging what the bound writer acknowledged while that one is matched.
//   The claimant is refused from then on, counted under runtime::kWriterConflicts (and
//   kWriterConflictsOn + topic) and named in one error line; heslam-supervisor fails the run on it
//   (runtime/supervisor/run_verdict.hpp). Which of the two is the forger cannot be known here.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <set>
#include <string>

#include <dds/dds.h>

#include "runtime/log.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/stats.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::runtime {

class RoleBinding {
 public:
  enum class Claim { kAccepted, kHeld, kRefused };

  // `topic`: the name the lines and the per-topic counter use.
  RoleBinding(const Logger& log, Stats& stats, std::string topic)
      : log_(log), stats_(stats), topic_(std::move(topic)) {}

  // A data sample of `writer` (read by `reader`, asked whether writers are still matched) that claims `role` (e.g.
  // "frontend", or "mapper" for any mapper name). `again`: a held sample asked about once more (never proof that its
  // writer is alive now). `subject`: what the sample acknowledges (a frame seq, a keyframe id): a claimant that
  // acknowledges what the bound writer acknowledged, before the caller is done() with it, while that one is matched is
  // a conflict at once (a forger that acknowledged first, the real one after it).
  Claim claim(dds_entity_t reader, const std::string& role, dds_instance_handle_t writer, std::uint64_t subject,
              bool again = false) {
    Role& bound = roles_[role];
    if (bound.owner == 0) bind(bound, writer);
    if (writer == bound.owner) {
      if (!again) {
        remember(bound, subject);
        for (const auto& [claimant, subjects] : bound.claimants) {
          if (writer_matched(reader, claimant)) conflict(reader, role, bound, claimant);
        }
        bound.claimants.clear();
      }
      return Claim::kAccepted;
    }
    if (bound.refused.count(writer) != 0) {
      stats_.count("refused_role_samples");
      return Claim::kRefused;
    }
    if (!writer_matched(reader, bound.owner)) {
      log_.info("topic '", topic_, "': role '", role, "' taken over by ", describe_writer(reader, writer),
                " (its writer ", describe_writer(reader, bound.owner), " left: a restarted component)");
      bind(bound, writer);
      stats_.count("role_take_overs");
      return Claim::kAccepted;
    }
    if (bound.subjects.count(subject) != 0) {
      conflict(reader, role, bound, writer);
      stats_.count("refused_role_samples");
      return Claim::kRefused;
    }
    bound.claimants[writer] = subject;
    return Claim::kHeld;
  }

  // The caller is done with `subject` (it moved on): a restarted component that acknowledges it again
  // within its predecessor's lease is no conflict.
  void done(std::uint64_t subject) {
    for (auto& [name, bound] : roles_) bound.subjects.erase(subject);
  }

  // Conflicts seen so far (both writers alive at once).
  std::uint64_t conflicts() const { return conflicts_; }

 private:
  // What a bound writer acknowledged, the latest kRememberedSubjects.
  static constexpr std::size_t kRememberedSubjects = 256;

  struct Role {
    dds_instance_handle_t owner = 0;
    std::set<std::uint64_t> subjects;                          // the owner's, recent
    std::deque<std::uint64_t> subject_order;                   // to forget the oldest
    std::map<dds_instance_handle_t, std::uint64_t> claimants;  // wrote while the owner was matched, not yet judged
    std::set<dds_instance_handle_t> refused;
  };

  void bind(Role& bound, dds_instance_handle_t writer) {
    bound.owner = writer;
    bound.claimants.erase(writer);
    bound.subjects.clear();
    bound.subject_order.clear();
  }

  void remember(Role& bound, std::uint64_t subject) {
    if (!bound.subjects.insert(subject).second) return;
    bound.subject_order.push_back(subject);
    if (bound.subject_order.size() > kRememberedSubjects) {
      bound.subjects.erase(bound.subject_order.front());  // a no-op when done() forgot it already
      bound.subject_order.pop_front();
    }
  }

  void conflict(dds_entity_t reader, const std::string& role, Role& bound, dds_instance_handle_t claimant) {
    bound.refused.insert(claimant);
    ++conflicts_;
    stats_.count(kWriterConflicts);
    stats_.count(std::string(kWriterConflictsOn) + topic_);
    log_.error("topic '", topic_, "': two live writers claim role '", role, "': ", describe_writer(reader, bound.owner),
               " (first) and ", describe_writer(reader, claimant),
               " (refused); a forged participant or a second copy of a component (counted as ", kWriterConflicts,
               "; the run fails)");
  }

  const Logger& log_;
  Stats& stats_;
  std::string topic_;
  std::map<std::string, Role> roles_;
  std::uint64_t conflicts_ = 0;
};

}  // namespace heslam::runtime
