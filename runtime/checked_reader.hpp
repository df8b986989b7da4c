// CheckedReader<T>: a Reader<T> for a topic a component trusts only from one writer, with every
// sample validated before it is handed out. Guards a run against hostile or mistaken participants on
// the same domain (a second replay, a stray tool, a sample full of NaN); docs/topics.md:
//
// - Validation: an optional check (the component's, e.g. frontend::check) returns what is wrong with
//   a sample; such a sample is dropped, counted under `rejected_counter` and reported by a
//   rate-limited warning naming the topic (Logger::warn_throttled).
// - One writer: the first writer whose sample arrives owns the stream. A sample of another writer
//   while the owner is still matched is held back, counted (`second_writer_samples`), and the
//   writer is announced once with one line naming the topic and both GUIDs. If the owner goes away
//   (deleted, or its process died and the 2 s lease expired), the writer whose held sample is the
//   oldest takes over and its held samples are handed out in arrival order: that is a restarted
//   publisher (the supervisor restarts a killed replay / mapper / loop closer well within a lease,
//   so its first samples arrive while the dead one still counts as matched). A hostile writer next
//   to a live owner never gets through. Held samples of writers that left too are dropped then.
//   Not handled: a hostile writer that is alive when the owner dies and was held first wins.
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
  // Samples of other writers kept for a possible take-over; the oldest go first when full. A
  // restarted mapper republishes its whole map at once, so map state readers need many.
  std::size_t max_held = 64;
};

// Counter of samples from a second writer (held back, and dropped unless it takes over).
inline constexpr const char* kSecondWriterSamples = "second_writer_samples";

template <Message T>
class CheckedReader {
 public:
  CheckedReader(const Participant& participant, const TopicSpec<T>& spec, const Logger& log, Stats& stats,
                SampleCheck<T> check, CheckedReaderOptions options = {}, std::optional<Qos> qos = std::nullopt)
      : reader_(participant, spec, qos), log_(log), stats_(stats), check_(std::move(check)), options_(std::move(options)) {}

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

  // Whether a take would return something (data in the reader, or held samples now released).
  bool has_unread() {
    if (!released_.empty() || reader_.has_unread()) return true;
    if (!held_.empty()) take_over_if_owner_left();
    return !released_.empty();
  }

  int matched_writers() const { return reader_.matched_writers(); }
  bool wait_for_writers(int count, std::chrono::milliseconds timeout) const { return reader_.wait_for_writers(count, timeout); }
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

  // True when `received` is the owner's (or carries no data); otherwise it is moved into held_.
  // Only data takes over a stream: a dispose notice is held like data but never makes its writer the
  // owner (a writer deleted at exit disposes its instances, and would otherwise own the topic).
  bool admit(Received<T>& received) {
    if (!options_.single_writer) return true;
    if (!received.info.valid_data && !received.info.disposed) return true;
    const dds_instance_handle_t writer = received.info.publication_handle;
    if (!owner_) {
      if (received.info.valid_data) owner_ = writer;
      return true;
    }
    if (writer == *owner_) return true;
    const bool owner_alive = writer_matched(handle(), *owner_);
    if (!owner_alive && received.info.valid_data) {
      take_over(writer);
      if (!released_.empty()) {  // older held samples of this writer go first
        released_.push_back(std::move(received));
        return false;
      }
      return true;
    }
    if (owner_alive && received.info.valid_data && announced_.insert(writer).second) {
      stats_.count("second_writers");
      log_.warn("topic '", name(), "': a second writer (", describe_writer(handle(), writer),
                ") while the run's first writer (", describe_writer(handle(), *owner_),
                ") is alive: its samples are ignored and counted as ", kSecondWriterSamples,
                " (it takes over only if the first one goes away, as a restarted publisher would)");
    }
    stats_.count(kSecondWriterSamples);
    if (held_.size() >= options_.max_held) held_.pop_front();
    held_.push_back(std::move(received));
    return false;
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
    const auto with_data = std::find_if(held_.begin(), held_.end(), [](const Received<T>& held) { return held.info.valid_data; });
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
    // Counted above as second_writer_samples; these are used after all.
    log_.info("topic '", name(), "': the first writer left; ", describe_writer(handle(), writer),
              " takes over (a restarted publisher), its ", released_.size(), " held samples are used");
  }

  Reader<T> reader_;
  const Logger& log_;
  Stats& stats_;
  SampleCheck<T> check_;
  CheckedReaderOptions options_;
  std::optional<dds_instance_handle_t> owner_;
  std::deque<Received<T>> held_;      // samples of other writers, arrival order
  std::deque<Received<T>> released_;  // held samples of a writer that took over, not yet taken
  std::set<dds_instance_handle_t> announced_;
};

}  // namespace heslam::runtime
