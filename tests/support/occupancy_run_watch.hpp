// A lockstep run with heslam-occupancy watched from a test: the keyframes made, the last frame the
// replay published and the frontend acknowledged (a run held by pausing the replay is settled when
// they are equal), and the occupancy process's last status (pid, counters). Used by the restart and
// the save-on-request tests; every wait is bounded against hangs, never a timing assertion.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"

namespace heslam::test {

struct OccupancyStatus {
  int pid = 0;
  std::map<std::string, std::uint64_t> counters;
  std::uint64_t counter(const std::string& name) const {
    const auto found = counters.find(name);
    return found == counters.end() ? 0 : found->second;
  }
  // Keyframes it is done with: a cloud made, or skipped (counted).
  std::uint64_t handled() const {
    return counter("clouds") + counter("keyframes_without_frame") + counter("keyframes_without_calibration") +
           counter("bad_frame_size");
  }
};

class OccupancyRunWatch {
 public:
  explicit OccupancyRunWatch(int domain, std::chrono::seconds timeout = std::chrono::seconds(120))
      : timeout_(timeout),
        participant_({.domain_id = domain, .dds_config = ""}),
        keyframes_(participant_, topics_.keyframes()),
        stereo_(participant_, topics_.stereo()),
        frame_done_(participant_, topics_.frame_done()),
        status_(participant_, topics_.status()) {}

  void poll() {
    for (auto& r : keyframes_.take()) {
      if (r.info.valid_data) keyframe_ids.insert(r.sample->id);
    }
    for (auto& r : stereo_.take()) {
      if (r.info.valid_data) last_frame_seq = r.sample->seq;
    }
    for (auto& r : frame_done_.take()) {
      if (r.info.valid_data) last_done_seq = r.sample->seq;
    }
    for (auto& r : status_.take()) {
      if (!r.info.valid_data || runtime::to_string(r.sample->name) != "occupancy") continue;
      OccupancyStatus status;
      status.pid = r.sample->pid;
      for (const msg::Counter& c : runtime::view(r.sample->counters))
        status.counters[runtime::to_string(c.name)] = c.value;
      occupancy = status;
    }
  }
  // Polls until `done` holds; false after the timeout.
  template <typename Done>
  bool until(Done done) {
    const auto deadline = std::chrono::steady_clock::now() + timeout_;
    while (std::chrono::steady_clock::now() < deadline) {
      poll();
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  // Held (the replay paused): the last frame acknowledged and every keyframe so far handled.
  bool settled() const {
    return last_frame_seq && last_done_seq == last_frame_seq && occupancy &&
           occupancy->handled() == keyframe_ids.size();
  }
  std::uint64_t counter(const std::string& name) const { return occupancy ? occupancy->counter(name) : 0; }

  std::set<std::uint64_t> keyframe_ids;
  std::optional<std::uint64_t> last_frame_seq, last_done_seq;
  std::optional<OccupancyStatus> occupancy;

 private:
  std::chrono::seconds timeout_;
  runtime::Topics topics_;
  runtime::Participant participant_;
  runtime::Reader<msg::Keyframe> keyframes_;
  runtime::Reader<msg::StereoFrame> stereo_;
  runtime::Reader<msg::FrameDone> frame_done_;
  runtime::Reader<msg::ComponentStatus> status_;
};

}  // namespace heslam::test
