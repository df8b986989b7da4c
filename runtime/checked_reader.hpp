// CheckedReader<T>: a Reader<T> for a topic a component trusts only from one writer, with every
// sample validated before it is handed out. Guards a run against hostile or mistaken participants on
// the same domain (a second replay, a stray tool, a sample full of NaN); docs/topics.md:
//
// - Validation: an optional check (the component's, e.g. messages::check) returns what is wrong with
//   a sample; such a sample is dropped, counted under `rejected_counter` and reported by a
//   rate-limited warning naming the topic (Logger::warn_throttled).
// - One writer: the first writer whose sample arrives owns the stream (in a run on one host, the
//   first writer of this process's run: runtime/run_id.hpp, run_on_one_host()). Every sample of another
//   writer is counted (`second_writer_samples`) and the writer is announced once with one line
//   naming the topic, both GUIDs and both runs.
// - Who may take over: only a writer of the owner's run (the run id every Writer carries in its user
//   data, runtime/run_id.hpp: the supervisor's pid and start time, the same for a component it
//   restarted). A writer of another run can never own the stream: its samples are dropped on arrival
//   (`other_run_writers` counts such writers). A sample of a writer of the owner's run while the
//   owner is still matched is held back; if the owner goes away (deleted, or its process died and
//   the 2 s lease expired), the one with the oldest held sample takes over and its held samples are
//   handed out in arrival order (`take_overs`): that is a restarted publisher (the supervisor
//   restarts a killed replay / mapper / loop closer well within a lease, so its first samples arrive
//   while the dead one still counts as matched). So an owner that leaves at the end of the run is
//   never replaced by a stray that is still alive, whatever the order in which processes exit.
//   Held samples of writers that left too are dropped at a take-over.
//
// - Two live writers: when the owner writes again while a writer of its run that was held back is
//   still matched, both are alive at once (a restarted publisher's predecessor never writes again):
//   counted as runtime::kWriterConflicts, one error line, the claimant refused; the run fails
//   (a participant that copied the run id).
//
// Invalid-data notices without a dispose (a writer unregistered / left) carry no data and pass.
#pragma once

#include <algorithm>
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "runtime/log.hpp"
#include "runtime/reader.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/run_id.hpp"
#include "runtime/stats.hpp"
#include "runtime/writer_identity.hpp"

namespace heslam::runtime {

// What is wrong with a sample (one phrase naming the field), or nothing when it is usable.
template <Message T>
using SampleCheck = std::function<std::optional<std::string>(const T&)>;

struct CheckedReaderOptions {
  // Counter and throttle class of samples the check rejects, e.g. "rejected_keyframes".
  std::string rejected_counter = "rejected_samples";
  // Whether the topic has one writer (all heslam data topics but KeyframeDone and status).
  bool single_writer = true;
  // Samples of other writers of the owner's run kept for a possible take-over; the oldest go first
  // when full. A restarted mapper republishes its whole map at once, so map state readers need many.
  std::size_t max_held = 64;
};

// Counter of samples from a second writer (held back, and dropped unless it takes over).
inline constexpr const char* kSecondWriterSamples = "second_writer_samples";
// Counter of writers other than the owner, announced once each.
inline constexpr const char* kSecondWriters = "second_writers";
// Counter of second writers of another run than the owner's: never take over, samples dropped.
inline constexpr const char* kOtherRunWriters = "other_run_writers";
// Counter of take-overs by a writer of the owner's run (a restarted publisher).
inline constexpr const char* kTakeOvers = "take_overs";

template <Message T>
class CheckedReader {
 public:
  CheckedReader(const Participant& participant, const TopicSpec<T>& spec, const Logger& log, Stats& stats,
                SampleCheck<T> check, CheckedReaderOptions options = {}, std::optional<Qos> qos = std::nullopt)
      : reader_(participant, spec, qos),
        log_(log),
        stats_(stats),
        check_(std::move(check)),
        options_(std::move(options)) {}

  // Up to max_samples admitted samples, oldest first (held samples of a writer that took over first).
  std::vector<Received<T>> take(std::size_t max_samples = kDefaultBatch) {
    std::vector<Received<T>> out;
    while (out.size() < max_samples) {
      Received<T> received;
      if (!take_into(received)) break;
      out.push_back(std::move(received));
    }
    return out;
  }

  // The next admitted sample into `received` (reusing its buffers when it comes from the reader).
  bool take_into(Received<T>& received) {
    if (released_.empty() && !held_.empty()) take_over_if_owner_left();
    if (!released_.empty()) {
      received = std::move(released_.front());
      released_.pop_front();
      return true;
    }
    while (reader_.take_into(received)) {
      if (!valid(received)) continue;
      if (admit(received)) return true;
      received = Received<T>{};  // moved into held_
    }
    return false;
  }

  // Whether samples of a possible successor are held back (a writer of the owner's run while the
  // owner still counts as matched, e.g. a restarted publisher within the killed one's lease).
  bool holds_samples() const { return !held_.empty(); }

  // Whether a take would return something (data in the reader, or held samples now released).
  bool has_unread() {
    if (!released_.empty() || reader_.has_unread()) return true;
    if (!held_.empty()) take_over_if_owner_left();
    return !released_.empty();
  }

  int matched_writers() const { return reader_.matched_writers(); }
  bool wait_for_writers(int count, std::chrono::milliseconds timeout) const {
    return reader_.wait_for_writers(count, timeout);
  }
  uint64_t schema_mismatches() const { return reader_.schema_mismatches(); }
  const std::string& name() const { return reader_.name(); }
  dds_entity_t handle() const { return reader_.handle(); }
  // The writer that owns the stream (0 before the first sample).
  dds_instance_handle_t owner() const { return owner_.value_or(0); }

 private:
  static constexpr std::size_t kDefaultBatch = 64;

  bool valid(const Received<T>& received) {
    if (!received.info.valid_data || !check_) return true;
    std::optional<std::string> problem = check_(*received.sample);
    if (!problem) return true;
    stats_.count(options_.rejected_counter);
    log_.warn_throttled(options_.rejected_counter, "topic '", name(), "': rejected a sample from ",
                        describe_writer(handle(), received.info.publication_handle), ": ", *problem, " (counted as ",
                        options_.rejected_counter, ")");
    return false;
  }

  // True when `received` is the owner's (or carries no data); otherwise it is dropped (a writer of
  // another run) or moved into held_ (a writer of the owner's run, a possible successor).
  // Only data takes over a stream: a dispose notice is held like data but never makes its writer the
  // owner (a writer deleted at exit disposes its instances, and would otherwise own the topic).
  bool admit(Received<T>& received) {
    if (!options_.single_writer) return true;
    if (!received.info.valid_data && !received.info.disposed) return true;
    const dds_instance_handle_t writer = received.info.publication_handle;
    if (!owner_) {
      if (!received.info.valid_data) return true;
      if (run_on_one_host() && run_of(writer) != process_run_id()) {
        // Another run on the domain that wrote before this run's own writer: never the owner.
        stats_.count(kSecondWriterSamples);
        if (announced_.insert(writer).second) {
          stats_.count(kSecondWriters);
          stats_.count(kOtherRunWriters);
          log_.warn("topic '", name(), "': a writer of another run (", describe_writer(handle(), writer), ", run ",
                    run_of(writer).value_or("unknown: it left"), "; this run is ", process_run_id(),
                    "): its samples are dropped and counted as ", kSecondWriterSamples);
        }
        return false;
      }
      own(writer);
      return true;
    }
    if (writer == *owner_) {
      if (received.info.valid_data) judge_claimants();
      return true;
    }
    if (refused_.count(writer) != 0) {
      stats_.count(kSecondWriterSamples);
      return false;
    }
    if (!of_owners_run(writer)) {
      stats_.count(kSecondWriterSamples);
      if (announced_.insert(writer).second) {
        stats_.count(kSecondWriters);
        stats_.count(kOtherRunWriters);
        log_.warn("topic '", name(), "': a second writer (", describe_writer(handle(), writer), ", run ",
                  run_of(writer).value_or("unknown: it left"), ") of another run than the stream's writer (",
                  describe_writer(handle(), *owner_), ", run ", owner_run_,
                  "): its samples are dropped and counted as ", kSecondWriterSamples,
                  "; it never takes the topic over (only a restarted publisher of the same run does)");
      }
      return false;
    }
    const bool owner_alive = writer_matched(handle(), *owner_);
    if (!owner_alive && received.info.valid_data) {
      take_over(writer);
      if (!released_.empty()) {  // older held samples of this writer go first
        released_.push_back(std::move(received));
        return false;
      }
      return true;
    }
    if (owner_alive && received.info.valid_data) claimants_.insert(writer);
    if (owner_alive && received.info.valid_data && announced_.insert(writer).second) {
      stats_.count(kSecondWriters);
      log_.warn("topic '", name(), "': a second writer (", describe_writer(handle(), writer),
                ") of the same run while the run's first writer (", describe_writer(handle(), *owner_),
                ") is alive: its samples are held back and counted as ", kSecondWriterSamples,
                " (it takes over only if the first one goes away, as a restarted publisher would)");
    }
    stats_.count(kSecondWriterSamples);
    if (held_.size() >= options_.max_held) held_.pop_front();
    held_.push_back(std::move(received));
    return false;
  }

  // The owner wrote again: a writer of its run that wrote since (held back) and is still matched is
  // alive too, so both claim the stream at once (a restarted publisher's predecessor is dead and never
  // writes again): a conflict, the run fails (runtime/run_counters.hpp). The claimant is refused from
  // now on; which of the two is a forger (one that copied the run id) cannot be known here.
  void judge_claimants() {
    for (const dds_instance_handle_t claimant : claimants_) {
      if (!writer_matched(handle(), claimant)) continue;
      refused_.insert(claimant);
      std::erase_if(held_, [&](const Received<T>& held) { return held.info.publication_handle == claimant; });
      stats_.count(kWriterConflicts);
      stats_.count(std::string(kWriterConflictsOn) + name());
      log_.error("topic '", name(), "': two live writers of run ", owner_run_,
                 " at once: ", describe_writer(handle(), *owner_), " (first) and ", describe_writer(handle(), claimant),
                 " (refused); a forged participant that copied the run id, or a second copy of the component "
                 "(counted as ",
                 kWriterConflicts, "; the run fails)");
    }
    claimants_.clear();
  }

  // `writer` owns the stream from its first sample on; its run decides who may succeed it. When it
  // left before it could be asked, the run is this process's (a reader expects its own run's data).
  void own(dds_instance_handle_t writer) {
    owner_ = writer;
    owner_run_ = run_of(writer).value_or(process_run_id());
  }

  // The run `writer` advertises ("" for none); nothing once it is no longer matched. Asked once per
  // writer while it is matched (a writer's QoS does not change).
  std::optional<std::string> run_of(dds_instance_handle_t writer) {
    const auto known = runs_.find(writer);
    if (known != runs_.end()) return known->second;
    std::optional<std::string> run = writer_run_id(handle(), writer);
    if (run) runs_.emplace(writer, *run);
    return run;
  }

  // Whether `writer` may succeed the owner: it is of the owner's run. A writer that left is not (it
  // cannot come back; a restart is a new writer).
  bool of_owners_run(dds_instance_handle_t writer) {
    const std::optional<std::string> run = run_of(writer);
    return run && *run == owner_run_;
  }

  void take_over_if_owner_left() {
    if (owner_ && writer_matched(handle(), *owner_)) return;
    // Samples of writers that left as well are stale (a stray publisher that has exited): dropped,
    // or a restart of the run's writer would hand out a dead stray's high-seq frame.
    std::map<dds_instance_handle_t, bool> alive;
    std::erase_if(held_, [&](const Received<T>& held) {
      const dds_instance_handle_t writer = held.info.publication_handle;
      auto it = alive.find(writer);
      if (it == alive.end()) it = alive.emplace(writer, writer_matched(handle(), writer)).first;
      return !it->second;
    });
    const auto with_data =
        std::find_if(held_.begin(), held_.end(), [](const Received<T>& held) { return held.info.valid_data; });
    if (with_data != held_.end()) take_over(with_data->info.publication_handle);
  }

  // `writer` owns the stream from now on; its held samples are released in arrival order.
  void take_over(dds_instance_handle_t writer) {
    owner_ = writer;
    std::deque<Received<T>> others;
    for (Received<T>& held : held_) {
      (held.info.publication_handle == writer ? released_ : others).push_back(std::move(held));
    }
    held_ = std::move(others);
    announced_.erase(writer);
    claimants_.erase(writer);
    stats_.count(kTakeOvers);
    // Counted above as second_writer_samples; these are used after all.
    log_.info("topic '", name(), "': the first writer left; ", describe_writer(handle(), writer), " of the same run (",
              owner_run_, ") takes over (a restarted publisher), its ", released_.size(), " held samples are used");
  }

  Reader<T> reader_;
  const Logger& log_;
  Stats& stats_;
  SampleCheck<T> check_;
  CheckedReaderOptions options_;
  std::optional<dds_instance_handle_t> owner_;
  std::string owner_run_;                              // the run of the owner (and its successors)
  std::map<dds_instance_handle_t, std::string> runs_;  // writers' runs, asked while they were matched
  std::deque<Received<T>> held_;                       // samples of other writers, arrival order
  std::deque<Received<T>> released_;                   // held samples of a writer that took over, not yet taken
  std::set<dds_instance_handle_t> announced_;
  std::set<dds_instance_handle_t> claimants_;  // of the owner's run, held while the owner was matched
  std::set<dds_instance_handle_t> refused_;    // claimants found alive with the owner: conflicts
};

}  // namespace heslam::runtime
